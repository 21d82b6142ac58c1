"""Golden images: each view of ``views.py`` rendered now is compared with ``tests/golden/<name>.png``.

Metric (per view, on the uint8 RGB picture, 160×90): ``d`` = per-pixel maximum over the channels of
|expected − actual|. The view FAILS when either
  * more than ``MAX_BAD_FRACTION`` = 1.0 % of the pixels have ``d`` > ``PIXEL_TOLERANCE`` = 16/255, or
  * the mean absolute difference over all pixels and channels exceeds ``MAX_MEAN_DIFF`` = 1.0/255.
Why: driver noise (another Mesa/llvmpipe version, another CPU's float rounding) is a sprinkle of 1–2 LSB
differences (stays under 16, adds well under 1 LSB to the mean) plus a few edge pixels that flip between two
surfaces (large d, but few of them). A broken effect changes a region — many pixels by much — or shifts the whole
picture a little (caught by the mean). Measured on llvmpipe at the pre-refactor commit, metric = (% pixels with
d > 16, mean |diff| in 1/255):
  noise:  re-render, same or another process ............................. (0 %, 0)      byte-identical
          camera.fov_deg +0.02° (sub-pixel geometry shift: edge pixels) .. ≤ 0.44 %, ≤ 0.39
          time_of_day.hour +0.002 (7 s of sun: shading/shadow-map LSBs) .. ≤ 0.21 %, ≤ 0.54
          rain.rate_mm_h × 1.0001: effect views ≤ 0.01 %, but frame_driver 10.5 % (mean 5.1): a changed input
          re-draws which drops spawn where — an input change, not noise (same seed + inputs give the same bytes)
  broken: the view's effect disabled: road 41 %, rainfall 4.3 % (mean 2.9), spray 6.4 %, windshield 7.3 %,
          atmosphere 33 %; in frame_driver windshield off 9.2 %, atmosphere off 35 % (rainfall 0.14 %, spray 0.43 %
          stay under: their own views catch them). Weakened (rainfall brightness, spray strength, windshield
          refraction, atmosphere glow × 0.5): 1.3 %, 4.6 %, 2.0 %, 1.8 %. Zero alpha in rainfall_streak.frag
          failed `rainfall` (4.30 %, mean 2.94) and `frame_chase` (mean 1.26).
So 1 % sits ~2× above the largest noise and ≥ 4× below an effect switched off. The ripples view is the exception:
the ripple field changes its picture by ≤ 1 LSB (even at maximum strengths), so it guards the wet road around the
wakes but cannot see a broken ripple solver (see README).

On failure the expected / actual / diff (|d| × 4) PNGs are written to ``tests/golden/_failures/`` (gitignored)
and the assertion message names them. After an intended change: ``python -m pytest tests/golden --update-golden``.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

GOLDEN_DIR = Path(__file__).resolve().parent
FAILURE_DIR = GOLDEN_DIR / "_failures"
PIXEL_TOLERANCE = 16  # 1/255: a pixel "differs" when some channel is off by more than this
MAX_BAD_FRACTION = 0.01  # fail when more than this fraction of pixels differ
MAX_MEAN_DIFF = 1.0  # 1/255: fail when the mean absolute difference (all pixels and channels) exceeds this


def _load_views():
    """views.py beside this file (the suite runs with --import-mode=importlib, so the folder is not on sys.path)."""
    name = "rainroad_golden_views"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, GOLDEN_DIR / "views.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


views = _load_views()


def compare(expected: np.ndarray, actual: np.ndarray) -> dict:
    """The metric: bad_fraction (pixels with d > PIXEL_TOLERANCE), mean_diff (1/255), max_diff, ok."""
    if expected.shape != actual.shape:
        return {"ok": False, "bad_fraction": 1.0, "mean_diff": 255.0, "max_diff": 255,
                "shape": (expected.shape, actual.shape)}
    diff = np.abs(expected.astype(np.int16) - actual.astype(np.int16))
    d = diff.max(axis=2)
    bad = float((d > PIXEL_TOLERANCE).mean())
    mean = float(diff.mean())
    return {"ok": bad <= MAX_BAD_FRACTION and mean <= MAX_MEAN_DIFF, "bad_fraction": bad, "mean_diff": mean,
            "max_diff": int(d.max())}


def _read_png(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _write_png(path: Path, image: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(np.ascontiguousarray(image, dtype=np.uint8)).save(path, optimize=True)


def _write_failure(name: str, expected: np.ndarray, actual: np.ndarray) -> list[Path]:
    FAILURE_DIR.mkdir(exist_ok=True)
    paths = [FAILURE_DIR / f"{name}.{kind}.png" for kind in ("expected", "actual", "diff")]
    _write_png(paths[0], expected)
    _write_png(paths[1], actual)
    if expected.shape == actual.shape:
        d = np.abs(expected.astype(np.int16) - actual.astype(np.int16)).max(axis=2)
        _write_png(paths[2], np.repeat(np.clip(d * 4, 0, 255)[..., None], 3, axis=2))
    else:
        paths.pop()
    return paths


@pytest.mark.parametrize("name", list(views.VIEWS))
def test_golden(gl_ctx, update_golden, name):
    actual = views.render_view(gl_ctx, name)
    path = GOLDEN_DIR / f"{name}.png"
    if update_golden:
        _write_png(path, actual)
        return
    if not path.exists():
        pytest.fail(f"no golden image {path}: run python -m pytest tests/golden --update-golden")
    expected = _read_png(path)
    result = compare(expected, actual)
    if not result["ok"]:
        written = _write_failure(name, expected, actual)
        pytest.fail(f"golden view {name!r} ({views.VIEWS[name].doc}) differs: "
                    f"{100 * result['bad_fraction']:.2f} % of pixels off by > {PIXEL_TOLERANCE}/255 "
                    f"(limit {100 * MAX_BAD_FRACTION:.1f} %), mean |diff| {result['mean_diff']:.2f}/255 "
                    f"(limit {MAX_MEAN_DIFF}), max {result['max_diff']}/255. "
                    f"Images: {', '.join(str(p) for p in written)}")
