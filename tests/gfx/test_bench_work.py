"""The GPU-work benchmark (``python -m rain_core.bench work``): each pass's fragments and primitives, counted by
GL queries, against what its draws must give (a full-screen pass writes every pixel once; the streaks assemble a
point and two triangles per drop instance), and the totals against their passes."""

from __future__ import annotations

import json

import pytest

from rain_core.bench.work import FRAME_ROW, RAIN_ROW, count_case, main, parse_args

SIZE = (64, 36)


@pytest.fixture(scope="module")
def rainy(gl_ctx):
    # Made before the per-test fixture that makes the shared context current (a module's fixtures come first):
    # current here too, and no GL error left behind.
    with gl_ctx:
        result = count_case(gl_ctx, SIZE, budget=3000, speed_kmh=100.0, frames=2, warmup=3)
        assert gl_ctx.error == "GL_NO_ERROR"
    return result


def test_full_screen_passes_write_each_pixel_once(rainy):
    rows = rainy["rows"]
    assert rows["tonemap"] == {"fragments": SIZE[0] * SIZE[1], "primitives": 1, "screens": 1.0}
    # the sky covers every pixel, then the depth pre-pass and the lit pass the meshes: at least a screen
    assert rows["scene"]["screens"] >= 1.0 and rows["scene"]["primitives"] > 1000


def test_streaks_assemble_a_point_and_two_triangles_per_drop_instance(rainy):
    n, splashes = rainy["streak_instances"], rainy["splash_instances"]
    assert n >= 3000 and splashes > 0
    prims = rainy["rows"]["rainfall.transparent"]["primitives"]
    # the record pass's points, the quads' triangle pairs, the splashes' pairs and the drop environment's triangle
    assert 3 * n + 2 * splashes <= prims <= 3 * n + 2 * splashes + 2
    assert 0 < rainy["rows"]["rainfall.transparent"]["fragments"] < 50 * SIZE[0] * SIZE[1]


def test_totals_add_up_their_passes(rainy):
    rows = rainy["rows"]
    passes = [rows[name] for name in rainy["passes"]]
    for key in ("fragments", "primitives"):
        assert rows[FRAME_ROW][key] == sum(r[key] for r in passes)
        rain = [rows[n][key] for n in rainy["passes"]
                if n.split(".")[0] in ("rainfall", "spray", "drips", "windshield", "ripples")]
        assert rows[RAIN_ROW][key] == sum(rain) > 0
        assert rows["effect: rainfall"][key] == sum(rows[n][key] for n in rainy["passes"] if n.startswith("rainfall."))


def test_a_dry_frame_draws_no_rain(gl_ctx):
    dry = count_case(gl_ctx, SIZE, budget=3000, speed_kmh=0.0, frames=1, warmup=1,
                     overrides=(("rain.rate_mm_h", 0.0), ("rain.wetness", 0.0), ("rain.puddles", 0.0)))
    assert "rainfall.transparent" not in dry["rows"] and "spray.transparent" not in dry["rows"]
    assert dry["rows"]["tonemap"]["fragments"] == SIZE[0] * SIZE[1]


def test_main_writes_its_tables(gl_ctx, tmp_path, capsys):
    assert main(["--quick", "--size", "48x27", "--warmup", "1", "--out", str(tmp_path)]) == 0
    results = json.loads((tmp_path / "work.json").read_text())
    assert [(r["budget"], r["speed_kmh"]) for r in results] == [(10_000, 100.0)]
    md = (tmp_path / "work.md").read_text()
    assert "| tonemap | 0.001 | 1.00 | 1 |" in md and "GL_SAMPLES_PASSED" in md
    assert "spray.update" not in md  # a pass without draws: in the JSON only


@pytest.mark.parametrize("argv, message", [
    (["--frames", "0"], "--frames must be in [1, 100]"),
    (["--speeds", "fast"], "--speeds must be comma-separated km/h"),
    (["--speeds", "-5"], "--speeds must be in [0, 250]"),
    (["--budgets", "2000000"], "--budgets must be in [0, 1000000]"),
    (["--set", "rain.rate_mm_h=-1"], "rain.rate_mm_h"),
])
def test_bad_arguments_name_the_flag(argv, message, capsys):
    with pytest.raises(SystemExit):
        parse_args(argv)
    assert message in capsys.readouterr().err
