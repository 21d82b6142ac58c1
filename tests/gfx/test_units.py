"""The texture-unit table: what one draw samples never shares a unit, and every unit fits GL 3.3's minimum."""

from rain_core.gfx import units

GL33_MIN_COMBINED_UNITS = 48  # GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS is at least 48 in OpenGL 3.3 core
GL33_MIN_FRAGMENT_UNITS = 16  # GL_MAX_TEXTURE_IMAGE_UNITS: what one fragment shader may sample


def _all_units() -> dict[str, int]:
    out = {}
    for name, value in vars(units).items():
        if name.isupper() and name != "SCENE_SHADER":
            for i, unit in enumerate(value if isinstance(value, tuple) else (value,)):
                out[f"{name}[{i}]" if isinstance(value, tuple) else name] = unit
    return out


def test_the_scene_shader_samples_distinct_units():
    assert len(set(units.SCENE_SHADER)) == len(units.SCENE_SHADER)


def test_effect_units_do_not_overlap_each_other_or_the_scene_shaders():
    # Scratch units are shared on purpose (offscreen passes bind right before drawing); all others are owned.
    owned = {k: v for k, v in _all_units().items() if not k.startswith(("SCRATCH", "IMAGE"))}
    by_unit: dict[int, list[str]] = {}
    for name, unit in owned.items():
        by_unit.setdefault(unit, []).append(name)
    shared = {u: names for u, names in by_unit.items() if len(names) > 1}
    assert not shared, f"texture units claimed twice: {shared}"


def test_every_unit_exists_on_any_gl33_driver():
    # A sampler uniform may name any unit below MAX_COMBINED_TEXTURE_IMAGE_UNITS (GL 3.3 core, 2.11.7); one
    # fragment shader may sample at most MAX_TEXTURE_IMAGE_UNITS of them.
    assert all(0 <= u < GL33_MIN_COMBINED_UNITS for u in _all_units().values())
    assert len(units.SCENE_SHADER) <= GL33_MIN_FRAGMENT_UNITS
