"""The rain effects, one folder each: the simulation in GL-free modules (NumPy only), the GL side in effect.py.

Every effect follows the contract of ``rain_core.gfx.effect`` and is built the same way:
``EffectClass(ctx, settings=None, *, seed=0, shaders=None)``.
"""

from __future__ import annotations


def effect_classes() -> tuple:
    """The effect classes in update and draw order. Order matters for ``rc.shared``: the road publishes the
    standing water, the spray its droplets landing in water, and the ripples read both and publish the water
    normals the road's scene binding reads."""
    from rain_core.effects.atmosphere import AtmosphereEffect
    from rain_core.effects.drips import DripsEffect
    from rain_core.effects.lightning import LightningEffect
    from rain_core.effects.rainbow import RainbowEffect
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.effects.ripples import RipplesEffect
    from rain_core.effects.road import RoadEffect
    from rain_core.effects.spray import SprayEffect
    from rain_core.effects.windshield import WindshieldEffect

    return (RoadEffect, SprayEffect, DripsEffect, RipplesEffect, RainfallEffect, RainbowEffect, LightningEffect,
            AtmosphereEffect, WindshieldEffect)


def default_effects(ctx, settings, seed: int = 0, shaders=None) -> list:
    """One instance of every effect, in order (each decides per frame whether it runs: ``active``)."""
    return [cls(ctx, settings, seed=seed, shaders=shaders) for cls in effect_classes()]
