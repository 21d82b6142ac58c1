from rain_core.ripples import RipplesEffect as _Ripples  # temporary forwarder until the ripples move here


def RipplesEffect(ctx, settings=None, *, seed=0, shaders=None):  # noqa: N802
    return _Ripples(ctx, settings, seed=seed)
