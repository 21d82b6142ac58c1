"""Scenario sweeps (issue 16): every combination of settings and seeds of a sweep file rendered into one
sequence folder each, on a local process pool or a Ray cluster, resumable, with a manifest a loader reads.

``load_sweep(path)`` reads and checks the file (``spec``), ``run_sweep(spec, out_dir, workers=, ray_address=)``
renders (``runner``); one sequence is ``sequence.render_sequence``; ``load_manifest(root)`` reads the results.
The command line is ``rainroad sweep SWEEP.toml --out DIR`` (app/sweep.py)."""

from rain_core.sweep.manifest import load_manifest
from rain_core.sweep.runner import run_sweep
from rain_core.sweep.sequence import folder_checksum, render_sequence
from rain_core.sweep.spec import Job, SweepError, SweepSpec, load_sweep

__all__ = ["Job", "SweepError", "SweepSpec", "folder_checksum", "load_manifest", "load_sweep", "render_sequence",
           "run_sweep"]
