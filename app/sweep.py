"""``rainroad sweep SWEEP.toml --out DIR`` (also ``python -m app sweep …``): render every sequence of a sweep file
(rain_core.sweep) on this machine's cores or on a Ray cluster. Bad input exits 2 before anything renders; Ctrl-C
exits 130 with the manifest consistent (rerun the same command to resume)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="rainroad sweep", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sweep", type=Path, help="the sweep file (TOML: [sweep], [grid], [[runs]]; see docs/sweeps.md)")
    p.add_argument("--out", type=Path, required=True, help="dataset root: one folder per sequence + manifest.jsonl")
    p.add_argument("--workers", type=int, default=1,
                   help="local worker processes, one GL context each (default 1); with --ray local: Ray's CPUs")
    p.add_argument("--ray", metavar="ADDRESS", dest="ray_address",
                   help='run on Ray: "auto" or "ray://host:port" for a running cluster (the --out folder must be '
                        'shared with it), "local" to start one here; needs pip install -e ".[scale]"')
    p.add_argument("--openscenario", type=Path, metavar="FILE.xosc",
                   help="base weather from an OpenSCENARIO file (overrides the sweep file's own)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    return p


def main(argv=None) -> int:
    from app.cli import check_output_folder
    from rain_core.sweep import SweepError, load_sweep, run_sweep

    parser = build_parser()
    args = parser.parse_args(argv)
    if not 1 <= args.workers <= 256:
        parser.error(f"argument --workers: must be in [1, 256], got {args.workers}")
    problem = check_output_folder(args.out)
    if problem:
        parser.error(f"argument --out: {problem}")
    try:
        spec = load_sweep(args.sweep, openscenario=args.openscenario)
    except SweepError as exc:
        parser.error(str(exc))
    if args.ray_address:
        try:
            import ray  # noqa: F401
        except ImportError:
            parser.error('argument --ray: Ray is not installed; pip install -e ".[scale]"')
    print(f"sweep: {len(spec.jobs)} sequences of {spec.frames} frames ({spec.size[0]}x{spec.size[1]}) -> {args.out}",
          file=sys.stderr)
    try:
        lines = run_sweep(spec, args.out, workers=args.workers, ray_address=args.ray_address,
                          progress=not args.quiet)
    except KeyboardInterrupt:
        print("\nsweep: interrupted; the manifest keeps what finished; run the same command to resume",
              file=sys.stderr)
        return 130
    failed = [line for line in lines if line["status"] != "complete"]
    print(f"sweep: {len(lines) - len(failed)} of {len(lines)} sequences complete in {args.out}", file=sys.stderr)
    for line in failed:
        print(f"sweep: failed {line['id']} {line['params']} seed {line['seed']}: {line['error']}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
