"""Run a sweep: skip what is done, render the rest on a local process pool or a Ray cluster, keep the manifest
consistent after every sequence, report progress.

Resuming: a sequence whose manifest line says complete, whose folder exists and whose files still hash to the
line's checksum is skipped; anything else (failed, interrupted, damaged) is rendered again. Leftover temporary
folders (``.tmp-*``, an interrupted sequence) are removed first.
"""

from __future__ import annotations

import shutil
import sys
import time
from pathlib import Path

from rain_core.interrupts import CtrlC
from rain_core.sweep.manifest import load_manifest, write_manifest
from rain_core.sweep.sequence import folder_checksum, render_sequence
from rain_core.sweep.spec import SweepSpec


def _job_payload(job) -> dict:
    return {"id": job.id, "params": dict(job.params), "seed": job.seed}


def _is_done(root: Path, line: dict | None) -> bool:
    if not line or line.get("status") != "complete" or not line.get("checksum"):
        return False
    folder = root / line["id"]
    return folder.is_dir() and folder_checksum(folder) == line["checksum"]


class Progress:
    """done/total, frames per second and the time left, on one line of ``stream`` (rewritten on a terminal)."""

    def __init__(self, total: int, frames_per_sequence: int, stream=None, enabled: bool = True):
        self.total, self.frames = total, frames_per_sequence
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.done = self.failed = 0
        self.start = time.perf_counter()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def update(self, line: dict) -> None:
        self.done += 1
        self.failed += line.get("status") != "complete"
        if not self.enabled:
            return
        elapsed = max(time.perf_counter() - self.start, 1e-9)
        rate = self.done * self.frames / elapsed
        left = (self.total - self.done) * elapsed / self.done
        text = (f"sweep: {self.done}/{self.total} sequences, {rate:.1f} frames/s, about {left:.0f} s left"
                + (f", {self.failed} failed" if self.failed else ""))
        if line.get("status") != "complete":
            print(f"\nsweep: {line['id']} failed {line.get('params')} seed {line.get('seed')}: {line.get('error')}",
                  file=self.stream)
        print(("\r" + text) if self.tty else text, end="" if self.tty else "\n", file=self.stream, flush=True)

    def close(self) -> None:
        if self.enabled and self.tty:
            print(file=self.stream)


def _local(spec: dict, jobs: list[dict], out: str, workers: int):
    """Yield finished lines from a pool of ``workers`` processes (spawned: each makes its own GL context)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [pool.submit(render_sequence, spec, job, out) for job in jobs]
        for future in as_completed(futures):
            yield future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _ray(spec: dict, jobs: list[dict], out: str, address: str, workers: int):
    """Yield finished lines from Ray tasks (one CPU each). address: a running cluster ("auto", "ray://host:port")
    or "local" for a Ray started here with ``workers`` CPUs. The output folder must be shared with the
    cluster's machines."""
    try:
        import ray
    except ImportError:
        raise RuntimeError('--ray needs Ray: pip install -e ".[scale]"') from None
    started = False
    if not ray.is_initialized():
        if address == "local":
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, log_to_driver=False)
        started = True
    task = ray.remote(num_cpus=1)(render_sequence)
    refs = [task.remote(spec, job, out) for job in jobs]
    try:
        while refs:
            ready, refs = ray.wait(refs, num_returns=1)
            yield ray.get(ready[0])
    finally:
        for ref in refs:
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()


def run_sweep(spec: SweepSpec, out_dir, workers: int = 1, ray_address: str | None = None,
              progress: bool = True, stream=None) -> list[dict]:
    """Render every sequence of ``spec`` not already complete into out_dir (created if missing); returns the
    manifest lines in the sweep's order. ``workers`` local processes, or Ray at ``ray_address``. A KeyboardInterrupt
    stops it with the manifest consistent (finished sequences kept, the rest pending) and is re-raised.
    The local pool spawns its workers: a script that calls this must guard its top level with
    ``if __name__ == "__main__":`` (as any multiprocessing program)."""
    root = Path(out_dir)
    root.mkdir(parents=True, exist_ok=True)
    for stale in root.glob(".tmp-*"):
        shutil.rmtree(stale, ignore_errors=True)
    known = load_manifest(root)
    lines: dict[str, dict] = {}
    pending = []
    for job in spec.jobs:
        line = known.get(job.id)
        if _is_done(root, line):
            lines[job.id] = line
        else:
            lines[job.id] = {"id": job.id, "params": dict(job.params), "seed": job.seed, "frames": 0,
                             "status": "pending", "checksum": None, "error": None, "seconds": 0.0}
            pending.append(_job_payload(job))
    order = [job.id for job in spec.jobs]
    write_manifest(root, [lines[i] for i in order])
    bar = Progress(len(pending), spec.frames, stream, progress)
    if not pending:
        return [lines[i] for i in order]
    payload = spec.to_dict()
    source = _ray(payload, pending, str(root), ray_address, max(1, int(workers))) if ray_address else \
        _local(payload, pending, str(root), max(1, int(workers)))
    ctrl_c = CtrlC().__enter__()
    try:
        for line in source:
            lines[line["id"]] = line
            write_manifest(root, [lines[i] for i in order])
            bar.update(line)
            ctrl_c.check()  # a Ctrl-C a finaliser dropped stops the sweep at the next finished sequence
    finally:
        ctrl_c.__exit__()
        bar.close()
        if hasattr(source, "close"):
            source.close()
    return [lines[i] for i in order]
