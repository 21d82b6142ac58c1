from rain_core.windshield import make_windshield  # temporary forwarder until the windshield moves here


def WindshieldEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return make_windshield(ctx, settings, shaders=shaders, seed=seed)
