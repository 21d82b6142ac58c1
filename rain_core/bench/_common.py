"""Shared benchmark helpers: timing, Markdown tables, output folder."""

from __future__ import annotations

import argparse
import json
import time
from contextlib import contextmanager
from pathlib import Path


def parser(name: str, description: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=f"python -m rain_core.bench {name}", description=description)
    p.add_argument("--out", default="bench_out", help="folder for the Markdown table and the plot")
    p.add_argument("--quick", action="store_true", help="fewer repetitions and sizes (for smoke tests)")
    return p


def add_jit_argument(p: argparse.ArgumentParser) -> None:
    """``--jit {auto,on,off}``: the CPU simulations' compiled kernels (rain_core.jit) or their NumPy twins, for
    before/after on one tree; ``apply_jit_argument`` sets it once the arguments are parsed."""
    p.add_argument("--jit", choices=("auto", "on", "off"), default="auto",
                   help="the CPU simulations' compiled kernels (auto: on where Numba is installed; off: their NumPy "
                        "twins, for before/after on one tree)")


def apply_jit_argument(p: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Turn the kernels on or off as ``--jit`` says (an error naming the flag where ``on`` finds no Numba)."""
    from rain_core import jit

    if args.jit != "auto":
        try:
            jit.set_active(args.jit == "on")
        except RuntimeError as exc:
            p.error(f"--jit on: {exc}")


def time_call(fn, repeat: int = 5, warmup: int = 1) -> float:
    """Median wall time of fn() in seconds."""
    for _ in range(warmup):
        fn()
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    samples.sort()
    return samples[len(samples) // 2]


def markdown_table(headers, rows) -> str:
    def fmt(v):
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def write_output(out_dir: str, name: str, markdown: str) -> Path:
    path = Path(out_dir)
    path.mkdir(parents=True, exist_ok=True)
    target = path / f"{name}.md"
    target.write_text(markdown + "\n")
    return target


def write_tables(out_dir: str | Path, name: str, markdown: str, data) -> None:
    """NAME.md (the tables) and NAME.json (``data``, the results in full) in ``out_dir``, and where they went."""
    target = write_output(out_dir, name, markdown)
    (target.parent / f"{name}.json").write_text(json.dumps(data, indent=1) + "\n")
    print(f"\nwrote {target} and {target.parent / f'{name}.json'}")


@contextmanager
def headless_run(out_dir: str | Path):
    """(output folder, headless GL context) for a benchmark's run: the folder made first (a bad one fails before
    the long work), the context released after."""
    from rain_core.gl import create_headless_context

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = create_headless_context()
    try:
        yield out, ctx
    finally:
        ctx.release()
