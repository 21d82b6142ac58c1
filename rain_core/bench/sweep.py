"""Sweep benchmark: sequences per hour on this machine with the local pool (1 and 2 workers) and under Ray
(started here), and what Ray adds per sequence.

``python -m rain_core.bench sweep [--quick] [--out DIR]``: a 2 × 2 grid (rate × seed), 2 s at 10 frames/s,
320×180 with labels (--quick: 0.5 s, 160×90). Ray rows only where Ray is installed (pip install -e ".[scale]").
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.sweep import load_sweep, run_sweep

SWEEP = """[sweep]
seconds = {seconds}
fps = 10
size = "{size}"
camera = "driver"
labels = true

[grid]
"rain.rate_mm_h" = [4.0, 16.0]
seed = [1, 2]
"""


def main(argv=None) -> int:
    args = parser("sweep", __doc__).parse_args(argv)
    seconds, size = (0.5, "160x90") if args.quick else (2.0, "320x180")
    work = Path(tempfile.mkdtemp(prefix="rainroad_sweep_bench_"))
    try:
        (work / "sweep.toml").write_text(SWEEP.format(seconds=seconds, size=size))
        spec = load_sweep(work / "sweep.toml")
        cases = [("pool, 1 worker", {"workers": 1}), ("pool, 2 workers", {"workers": 2})]
        try:
            import ray  # noqa: F401

            cases.append(("Ray (local), 2 CPUs", {"workers": 2, "ray_address": "local"}))
        except ImportError:
            pass
        rows, per_sequence = [], {}
        for label, kw in cases:
            out = work / label.replace(" ", "_").replace(",", "").replace("(", "").replace(")", "")
            t0 = time.perf_counter()
            lines = run_sweep(spec, out, progress=False, **kw)
            wall = time.perf_counter() - t0
            inside = sum(line["seconds"] for line in lines) / len(lines)
            failed = [line for line in lines if line["status"] != "complete"]
            if failed:
                print(f"{label}: {len(failed)} failed, e.g. {failed[0]['error']}")
            per_sequence[label] = wall / len(lines)
            rows.append((label, wall, 3600.0 * len(lines) / wall, inside,
                         "yes" if all(line["status"] == "complete" for line in lines) else "NO"))
        table = markdown_table(["backend", "wall s (4 sequences)", "sequences/hour", "s per sequence in a worker",
                                "all complete"], rows)
        note = ""
        if "Ray (local), 2 CPUs" in per_sequence:
            extra = per_sequence["Ray (local), 2 CPUs"] - per_sequence["pool, 2 workers"]
            note = (f"\nRay adds {extra:+.1f} s of wall time per sequence over the pool with the same 2 CPUs "
                    f"(its start-up spread over the sequences; a loaded machine makes this noisy).\n")
        md = (f"# Sweep\n\n4 sequences × {spec.frames} frames at {size} with labels, this machine:\n\n{table}\n"
              f"{note}")
        print(md)
        write_output(args.out, "sweep", md)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0
