from rain_core.spray import make_spray  # temporary forwarder until the spray moves here


def SprayEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return make_spray(ctx, settings)
