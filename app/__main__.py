"""``python -m app`` / ``rainroad``: the driving window, ``--headless`` rendering to PNG, or ``sweep``."""

from __future__ import annotations

import sys

from app.cli import parse_args
from rain_core.settings import Settings, apply_rain_preset, load_scenario, preset_settings, set_value

# Flag → settings field it sets; every value passes the settings validation.
FLAG_FIELDS = {"--rain-rate": ("rain_rate", "rain.rate_mm_h"), "--hour": ("hour", "time_of_day.hour"),
               "--camera": ("camera", "camera.mode"), "--traffic": ("traffic", "traffic.count")}


def settings_from_args(args) -> Settings:
    """Scenario file, then an OpenSCENARIO file's weather, then preset, then single flags. Bad input exits 2 with
    the flag and the reason."""
    fail = args.parser.error
    settings = Settings()
    try:
        if args.scenario is not None:
            settings = load_scenario(args.scenario)
    except (OSError, ValueError) as exc:
        fail(f"argument --scenario: {exc}")
    if getattr(args, "openscenario", None) is not None:
        import warnings

        from rain_core.openscenario import load as load_openscenario

        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                settings = load_openscenario(args.openscenario, base=settings)
            for w in caught:
                print(f"rainroad: warning: {w.message}", file=sys.stderr)
        except (OSError, ValueError) as exc:
            fail(f"argument --openscenario: {exc}")
    try:
        if args.preset is not None and args.scenario is not None:
            apply_rain_preset(settings, args.preset)  # the scenario keeps everything but the rain
        elif args.preset is not None:
            settings = preset_settings(args.preset)
    except (OSError, ValueError) as exc:
        fail(f"argument --preset: {exc}")
    for flag, (attr, path) in FLAG_FIELDS.items():
        value = getattr(args, attr)
        if value is not None:
            try:
                set_value(settings, path, value)
            except ValueError as exc:
                fail(f"argument {flag}: {exc}")
    return settings


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "sweep":  # rainroad sweep SWEEP.toml --out DIR
        from app.sweep import main as sweep_main

        return sweep_main(argv[1:])
    args = parse_args(argv)
    settings = settings_from_args(args)
    if args.headless:
        from app.headless import run_headless

        return run_headless(args, settings)
    from app.window import run_window

    return run_window(args, settings, max_frames=args.frames)


if __name__ == "__main__":
    sys.exit(main())
