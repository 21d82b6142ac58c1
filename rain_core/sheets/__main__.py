"""Dispatch ``python -m rain_core.sheets NAME [args]`` to rain_core.sheets.NAME.main(argv)."""

from __future__ import annotations

import importlib
import pkgutil
import sys

import rain_core.sheets as _pkg


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    names = sorted(m.name for m in pkgutil.iter_modules(_pkg.__path__) if not m.name.startswith("_"))
    if not argv or argv[0] not in [*names, "all"]:
        print("usage: python -m rain_core.sheets NAME [options]   (NAME: " + ", ".join(names) + ", all)",
              file=sys.stderr)
        return 2
    for name in names if argv[0] == "all" else [argv[0]]:
        rc = importlib.import_module(f"rain_core.sheets.{name}").main(argv[1:])
        if rc:
            return rc
    return 0


if __name__ == "__main__":
    sys.exit(main())
