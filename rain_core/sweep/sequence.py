"""One sequence of a sweep: render it into a temporary folder, then rename it into place (worker side).

A sequence folder holds the frames (frame_NNNNN.png), the labels (``rain_core.session.DatasetWriter``: depth,
masks and labels.jsonl, when the sweep asks for labels) and ``settings.toml``, the sequence's resolved settings.
Its checksum is the SHA-256 of every file's name and bytes, in name order — the manifest keeps it, and a rerun
recomputes it to tell a complete folder from a damaged one.

The pictures depend only on the sequence's parameters and seed: the ripple solver's backend is pinned (its
"auto" choice times the machine), and nothing reads a clock.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import time
from pathlib import Path

RIPPLE_BACKEND = "gpu"  # pinned: "auto" would pick by timing the machine, and the pictures would follow
_CONTEXT = None  # one GL context per worker process, made on its first sequence


def folder_checksum(folder: Path) -> str:
    """SHA-256 over the names and bytes of every file in ``folder`` (recursively), in sorted order."""
    digest = hashlib.sha256()
    for file in sorted(p for p in Path(folder).rglob("*") if p.is_file()):
        digest.update(file.relative_to(folder).as_posix().encode() + b"\0")
        with open(file, "rb") as handle:
            for chunk in iter(lambda h=handle: h.read(1 << 20), b""):
                digest.update(chunk)
    return digest.hexdigest()


def _context():
    global _CONTEXT
    if _CONTEXT is None:
        from rain_core.gfx.context import create_headless_context

        _CONTEXT = create_headless_context()
    return _CONTEXT


def render_sequence(spec: dict, job: dict, out_dir: str) -> dict:
    """Render ``job`` (``{"id", "params", "seed"}``) of the sweep ``spec`` (``SweepSpec.to_dict()``) into
    out_dir/<id>; returns the manifest line: id, params, seed, frames, status ("complete" or "failed"),
    checksum, error, seconds (wall time). Never raises for a failing sequence: the error is in the line."""
    out = Path(out_dir)
    start = time.perf_counter()
    tmp = out / f".tmp-{job['id']}-{os.getpid()}"
    line = {"id": job["id"], "params": job["params"], "seed": job["seed"], "frames": 0, "status": "failed",
            "checksum": None, "error": None, "seconds": 0.0}
    try:
        from PIL import Image

        from rain_core.session import DatasetWriter, Session
        from rain_core.settings import Settings, save_scenario, set_value

        settings = Settings.from_dict(spec["base"])
        for path, value in job["params"].items():
            set_value(settings, path, value)
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir(parents=True)
        save_scenario(settings, tmp / "settings.toml", title=f"sequence {job['id']}, seed {job['seed']}")
        frames = int(spec["frames"])
        dt = 1.0 / float(spec["fps"])
        with Session(size=tuple(spec["size"]), seed=int(job["seed"]), camera=spec["camera"], settings=settings,
                     ctx=_context()) as sim:
            for effect in sim.scene.effects:
                if getattr(effect, "name", "") == "ripples" and hasattr(effect, "backend"):
                    effect.backend = RIPPLE_BACKEND
            writer = DatasetWriter(tmp, spec["fps"], images=True) if spec["labels"] else None
            try:
                for i in range(frames):
                    sim.step(dt)
                    cap = sim.capture(labels=bool(spec["labels"]))
                    if writer is not None:
                        writer.add(cap)
                    else:
                        Image.fromarray(cap.rgb).save(tmp / f"frame_{i:05d}.png")
                    line["frames"] = i + 1
            finally:
                if writer is not None:
                    writer.close()
        line["checksum"] = folder_checksum(tmp)
        final = out / job["id"]
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)  # atomic: a folder with the final name is always complete
        line["status"] = "complete"
    except Exception as exc:  # a failing sequence is reported; the sweep goes on
        line["error"] = f"{type(exc).__name__}: {exc}"
        shutil.rmtree(tmp, ignore_errors=True)
    line["seconds"] = round(time.perf_counter() - start, 3)
    return line
