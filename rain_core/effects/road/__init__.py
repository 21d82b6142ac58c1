from rain_core.road import make_road  # temporary forwarder until the road moves here


def RoadEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return make_road(ctx, settings)
