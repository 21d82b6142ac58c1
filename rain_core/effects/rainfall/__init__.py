from rain_core.rainfall import make_rainfall  # temporary forwarder until the rainfall moves here


def RainfallEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return make_rainfall(ctx, settings, shaders=shaders, seed=seed)
