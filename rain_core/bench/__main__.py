"""Dispatch ``python -m rain_core.bench NAME [args]`` to the benchmark module rain_core.bench.NAME."""

from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path

import rain_core.bench as _pkg
from rain_core import checks
from rain_core.path_checks import check_output_folder, name_problem


def available() -> list[str]:
    return sorted(m.name for m in pkgutil.iter_modules(_pkg.__path__) if not m.name.startswith("_"))


def out_folder_problem(argv: list[str]) -> str | None:
    """Why the folder a run's ``--out`` names (``--out DIR`` or ``--out=DIR``; every benchmark's default is
    bench_out) cannot take its tables, or None: made now, with its parents, then checked as the command line checks
    its output folders (``path_checks.check_output_folder``). Before any long work, and as a message, not a
    traceback."""
    value = "bench_out"
    for i, arg in enumerate(argv):
        if arg == "--out" and i + 1 < len(argv):
            value = argv[i + 1]
        elif arg.startswith("--out="):
            value = arg[len("--out="):]
    folder = Path(value)
    problem = name_problem(folder)  # (a name too long: said as the command line says it, before mkdir fails on it)
    if problem is None:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except (OSError, ValueError) as exc:  # (ValueError: a NUL in the name)
            problem = f"cannot make it ({getattr(exc, 'strerror', None) or exc})"
        else:
            problem = check_output_folder(folder)
    return None if problem is None else f"--out {checks.quote(value)}: {problem}"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    names = available()
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m rain_core.bench NAME [options]   (NAME: " + ", ".join(names) + ", all)")
        return 0 if argv else 2
    name, rest = argv[0], argv[1:]
    targets = names if name == "all" else [name]
    problem = None if {"-h", "--help"} & set(rest) or not set(targets) <= set(names) else out_folder_problem(rest)
    if problem:
        print(f"rain_core.bench: {problem}", file=sys.stderr)
        return 2
    for target in targets:
        if target not in names:
            print(f"rain_core.bench: unknown benchmark {target!r}; choose from {', '.join(names)}", file=sys.stderr)
            return 2
        rc = importlib.import_module(f"rain_core.bench.{target}").main(rest)
        if rc:
            return rc
    return 0


if __name__ == "__main__":
    sys.exit(main())
