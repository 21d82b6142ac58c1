"""Dispatch ``python -m rain_core.bench NAME [args]`` to the benchmark module rain_core.bench.NAME."""

from __future__ import annotations

import importlib
import pkgutil
import sys

import rain_core.bench as _pkg


def available() -> list[str]:
    return sorted(m.name for m in pkgutil.iter_modules(_pkg.__path__) if not m.name.startswith("_"))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    names = available()
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m rain_core.bench NAME [options]   (NAME: " + ", ".join(names) + ", all)")
        return 0 if argv else 2
    name, rest = argv[0], argv[1:]
    targets = names if name == "all" else [name]
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
