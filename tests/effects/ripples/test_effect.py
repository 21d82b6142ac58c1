"""The ripples effect in the scene (issue 5), and the benchmark's quick run."""

from __future__ import annotations

import numpy as np

from rain_core.gfx.effect import Effect


class _Puddle(Effect):
    """Stands in for the road effect: publishes a film depth of 5 mm everywhere on the road."""

    name = "puddle"

    def active(self, frame):
        return True

    def update(self, frame, rc):
        rc.shared.film_depth_fn = lambda x, z: np.where(np.abs(np.asarray(x)) < 7.0, 5.0, 0.0)


def _ripple_scene(gl_ctx, puddles, rate=0.0):
    from rain_core.effects.ripples import RipplesEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in (("rain.rate_mm_h", rate), ("rain.puddles", puddles), ("rain.cracks", puddles),
                        ("quality.ripple_grid", 128), ("camera.mode", "chase")):
        set_value(settings, path, value)
    effect = RipplesEffect(gl_ctx, settings, seed=1)
    effect.backend = "numpy32"
    return Scene(gl_ctx, (64, 36), settings=settings, seed=1, effects=[_Puddle(), effect]), effect


def test_effect_skips_without_standing_water(gl_ctx):
    scene, effect = _ripple_scene(gl_ctx, puddles=0.0, rate=0.0)
    scene.step(1 / 30)
    scene.render()
    table = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
    assert table["ripples"] is False and effect.field is None
    scene.release()


def test_driving_through_water_leaves_a_wake_behind_the_wheels(gl_ctx):
    scene, effect = _ripple_scene(gl_ctx, puddles=1.0, rate=0.0)
    for _ in range(20):
        scene.step(1 / 30)
        scene.render()
    field = effect.field
    assert field.solver.energy() > 0 and np.isfinite(field.height).all()
    ego = scene.ego
    # The wake lies along the wheels' tracks behind the car, not beside the lane.
    track_x = ego.wheel_contacts()[0, 0]
    behind = [ego.position[2] + d for d in (3.0, 5.0, 7.0)]

    def disturbance(x, z):  # largest |height| within 2 cells of (x, z)
        ix, iz = (int(round(float(v))) for v in field.world_to_cell(x, z))
        return np.abs(field.height[iz - 2: iz + 3, ix - 2: ix + 3]).max()

    on_track = np.mean([disturbance(track_x, z) for z in behind])
    off_track = np.mean([disturbance(track_x - 6.0, z) for z in behind])
    assert on_track > 5 * off_track
    names = [row[0] for row in scene.renderer.pass_table()]
    assert "ripples.update" in names
    note = dict((row[0], row[4]) for row in scene.renderer.pass_table())["ripples.update"]
    assert "numpy32" in note
    scene.release()


def test_benchmark_quick_writes_table_and_plot(tmp_path, capsys):
    from rain_core.bench import ripples as bench

    assert bench.main(["--quick", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "ripples.md").read_text()
    assert "order vs continuous" in text and "chosen" in text and "asleep" in text
    assert (tmp_path / "ripples.png").stat().st_size > 1000
    orders = [float(line.split("|")[-2]) for line in text.splitlines()
              if line.startswith("| 256 |") and "NumPy float64" in line]
    assert orders and abs(orders[0] - 2.0) < 0.1
