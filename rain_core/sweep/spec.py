"""A sweep file: what every sequence shares and what varies, read and checked before anything renders.

```toml
[sweep]
seconds = 4.0            # per sequence, s (0 < s ≤ 3600)
fps = 30                 # frames per second (1…240)
size = "640x360"         # pixels (16…8192 each)
camera = "driver"        # driver | chase
labels = true            # depth, masks and per-frame labels beside each frame
scenario = "base.toml"   # optional, relative to this file: the settings every sequence starts from
openscenario = "s.xosc"  # optional: an OpenSCENARIO file's weather on top of that

[grid]                   # every combination (a cartesian product); "seed" is the sequence seed
"rain.rate_mm_h" = [0.5, 4, 16, 50]
"time_of_day.hour" = [12, 18.5, 22]
seed = [1, 2, 3]

[[runs]]                 # and/or a list: each table is one sequence (its own paths and seed)
"rain.rate_mm_h" = 8.0
seed = 7
```

Each combination is a ``Job`` with a stable id (its index and a hash of its parameters), so a rerun of the same
file finds the same folders.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from rain_core.settings import Settings, SettingsError, field_info, load_scenario, set_value

CAMERAS = ("driver", "chase")
SWEEP_KEYS = {"seconds", "fps", "size", "camera", "labels", "scenario", "openscenario"}
MAX_SEQUENCES = 100_000


class SweepError(ValueError):
    """A bad sweep file: the message names the file and the key."""


@dataclass(frozen=True)
class Job:
    """One sequence: its index in the sweep, its parameters (settings path → value) and seed."""

    index: int
    params: tuple[tuple[str, object], ...]
    seed: int

    @property
    def id(self) -> str:
        digest = hashlib.sha1(json.dumps([list(self.params), self.seed], sort_keys=True).encode()).hexdigest()
        return f"seq_{self.index:05d}_{digest[:8]}"

    def as_dict(self) -> dict:
        return {**dict(self.params), "seed": self.seed}


@dataclass
class SweepSpec:
    """The checked contents of a sweep file (see the module docstring)."""

    path: Path
    seconds: float
    fps: float
    size: tuple[int, int]
    camera: str
    labels: bool
    base: Settings
    jobs: list[Job] = field(default_factory=list)

    @property
    def frames(self) -> int:
        """Frames per sequence."""
        return max(1, int(round(self.seconds * self.fps)))

    def settings_for(self, job: Job) -> Settings:
        settings = self.base.copy()
        for path, value in job.params:
            set_value(settings, path, value)
        return settings

    def to_dict(self) -> dict:
        """What a worker needs (plain values, so it crosses process and machine boundaries)."""
        return {"seconds": self.seconds, "fps": self.fps, "size": list(self.size), "camera": self.camera,
                "labels": self.labels, "base": self.base.to_dict(), "frames": self.frames}


def _fail(path: Path, key: str, message: str):
    raise SweepError(f"{path}: {key}: {message}")


def _number(path: Path, table: dict, key: str, lo: float, hi: float, unit: str, default=None) -> float:
    value = table.get(key, default)
    if value is None:
        _fail(path, f"[sweep] {key}", f"missing ({unit}, in ({lo:g}, {hi:g}])")
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) \
            or not (lo < value <= hi):
        _fail(path, f"[sweep] {key}", f"must be a number in ({lo:g}, {hi:g}] {unit}, got {value!r}")
    return float(value)


def _size(path: Path, text) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in str(text).lower().split("x"))
    except ValueError:
        _fail(path, "[sweep] size", f'must be "WxH" in pixels, e.g. "640x360", got {text!r}')
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        _fail(path, "[sweep] size", f"each side must be in [16, 8192] px, got {text!r}")
    return w, h


def _check_value(path: Path, where: str, key: str, value, base: Settings) -> None:
    if key == "seed":
        if isinstance(value, bool) or not isinstance(value, int) or not (0 <= value <= 2**31 - 1):
            _fail(path, f"{where} seed", f"must be an integer in [0, 2147483647], got {value!r}")
        return
    try:
        field_info(key)
    except (KeyError, ValueError, SettingsError):
        _fail(path, f"{where} {key!r}", "is not a settings path (e.g. \"rain.rate_mm_h\"; see the scenario TOML)")
    try:
        set_value(base.copy(), key, value)
    except ValueError as exc:
        _fail(path, f"{where} {key!r}", str(exc))


def load_sweep(path, openscenario=None) -> SweepSpec:
    """Read and check the sweep file at ``path`` (every value of every combination is tried on the settings:
    a bad one fails here, naming the key and its allowed range, before any rendering). ``openscenario`` (a path)
    overrides the file's own."""
    path = Path(path)
    if not path.is_file():
        raise SweepError(f"{path}: no such sweep file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise SweepError(f"{path}: not a UTF-8 text file") from None
    unknown = set(data) - {"sweep", "grid", "runs"}
    if unknown:
        _fail(path, "top level", f"unknown table(s) {sorted(unknown)}; use [sweep], [grid] and [[runs]]")
    sweep = data.get("sweep", {})
    if not isinstance(sweep, dict):
        _fail(path, "[sweep]", "must be a table")
    extra = set(sweep) - SWEEP_KEYS
    if extra:
        _fail(path, "[sweep]", f"unknown key(s) {sorted(extra)}; allowed: {sorted(SWEEP_KEYS)}")
    seconds = _number(path, sweep, "seconds", 0.0, 3600.0, "s", default=4.0)
    fps = _number(path, sweep, "fps", 0.0, 240.0, "frames/s", default=30.0)
    size = _size(path, sweep.get("size", "640x360"))
    camera = sweep.get("camera", "driver")
    if camera not in CAMERAS:
        _fail(path, "[sweep] camera", f"must be one of {', '.join(CAMERAS)}, got {camera!r}")
    labels = sweep.get("labels", True)
    if not isinstance(labels, bool):
        _fail(path, "[sweep] labels", f"must be true or false, got {labels!r}")
    base = Settings()
    if sweep.get("scenario") is not None:
        try:
            base = load_scenario(path.parent / str(sweep["scenario"]))
        except (OSError, ValueError) as exc:
            _fail(path, "[sweep] scenario", str(exc))
    xosc = openscenario if openscenario is not None else sweep.get("openscenario")
    if xosc is not None:
        from rain_core.openscenario import load as load_openscenario

        xosc_path = Path(xosc) if openscenario is not None else path.parent / str(xosc)
        try:
            base = load_openscenario(xosc_path, base=base)
        except (OSError, ValueError) as exc:
            _fail(path, "[sweep] openscenario", str(exc))

    grid = data.get("grid", {})
    runs = data.get("runs", [])
    if not isinstance(grid, dict) or not isinstance(runs, list):
        _fail(path, "[grid]/[[runs]]", "[grid] must be a table of lists, [[runs]] a list of tables")
    combos: list[dict] = []
    if grid:
        keys = list(grid)
        for key in keys:
            values = grid[key]
            if not isinstance(values, list) or not values:
                _fail(path, f"[grid] {key!r}", f"must be a non-empty list of values, got {values!r}")
            for value in values:
                _check_value(path, "[grid]", key, value, base)
        count = math.prod(len(grid[k]) for k in keys)
        if count > MAX_SEQUENCES:
            _fail(path, "[grid]", f"{count} combinations; at most {MAX_SEQUENCES} per sweep")
        combos += [dict(zip(keys, values, strict=True)) for values in itertools.product(*(grid[k] for k in keys))]
    for i, run in enumerate(runs):
        if not isinstance(run, dict):
            _fail(path, f"[[runs]] #{i + 1}", "must be a table")
        for key, value in run.items():
            _check_value(path, f"[[runs]] #{i + 1}", key, value, base)
        combos.append(dict(run))
    if not combos:
        combos = [{}]
    jobs = []
    for index, combo in enumerate(combos):
        seed = int(combo.pop("seed", 1))
        jobs.append(Job(index, tuple(sorted(combo.items())), seed))
    return SweepSpec(path, seconds, fps, size, camera, labels, base, jobs)
