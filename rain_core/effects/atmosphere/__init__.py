from rain_core.atmosphere import make_atmosphere  # temporary forwarder until the atmosphere moves here


def AtmosphereEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return make_atmosphere(ctx, settings)
