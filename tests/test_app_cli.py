"""The command line: bad values exit 2 naming the flag; the headless run writes real pictures."""

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image


def run_app(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "app", *args], capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("args, flag", [
    (["--headless", "--size", "0x-5"], "--size"),
    (["--headless", "--size", "big"], "--size"),
    (["--headless", "--seconds", "nan"], "--seconds"),
    (["--headless", "--seconds", "-1"], "--seconds"),
    (["--headless", "--rain-rate", "inf"], "--rain-rate"),
    (["--headless", "--hour", "25"], "--hour"),
    (["--headless", "--traffic", "-3"], "--traffic"),
    (["--headless", "--preset", "monsoon"], "--preset"),
    (["--headless", "--scenario", "does/not/exist.toml"], "--scenario"),
    (["--screenshot", "x.png"], "--screenshot"),
])
def test_bad_values_exit_2_and_name_the_flag(args, flag):
    result = run_app(*args)
    assert result.returncode == 2, result.stderr
    assert flag in result.stderr
    assert "Traceback" not in result.stderr


def test_bad_scenario_file_names_field(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[rain]\nrate_mm_h = -4.0\n")
    result = run_app("--headless", "--scenario", str(bad))
    assert result.returncode == 2
    assert "--scenario" in result.stderr and "rain.rate_mm_h" in result.stderr


def test_headless_screenshot_and_record(tmp_path):
    shot = tmp_path / "out.png"
    rec = tmp_path / "rec"
    result = run_app("--headless", "--size", "96x64", "--seconds", "0.2", "--fps", "10", "--seed", "3",
                     "--screenshot", str(shot), "--record", str(rec))
    assert result.returncode == 0, result.stderr
    frames = sorted(rec.glob("frame_*.png"))
    assert [f.name for f in frames] == ["frame_00000.png", "frame_00001.png"]
    img = np.asarray(Image.open(shot))
    assert img.shape == (64, 96, 3)
    assert img.std() > 5.0  # a picture, not a flat colour
    np.testing.assert_array_equal(img, np.asarray(Image.open(frames[-1])))


@pytest.mark.parametrize("args, flag", [
    (["--headless", "--screenshot", "out.jpg"], "--screenshot"),
    (["--headless", "--screenshot", "/proc/nope/x.png"], "--screenshot"),
    (["--headless", "--record", "/etc/hostname"], "--record"),
    (["--window", "nope"], "--window"),
])
def test_bad_output_paths_and_backends_exit_2_before_rendering(args, flag):
    result = run_app(*args)
    assert result.returncode == 2, result.stderr
    assert flag in result.stderr and "Traceback" not in result.stderr


def test_preset_on_top_of_a_scenario_keeps_the_scenario(tmp_path):
    from app.__main__ import settings_from_args
    from app.cli import parse_args
    from rain_core.physics import RAIN_PRESETS

    scenario = tmp_path / "night.toml"
    scenario.write_text("[time_of_day]\nhour = 22.0\n")
    settings = settings_from_args(parse_args(["--headless", "--scenario", str(scenario), "--preset", "heavy"]))
    assert settings.time_of_day.hour == 22.0 and settings.rain.rate_mm_h == RAIN_PRESETS["heavy"]


def test_held_keys_release_independently_and_a_release_is_never_lost():
    from app.controls import KeyboardDriver

    driver = KeyboardDriver()
    driver.press("up", "W")
    driver.press("up", "UP")
    driver.release("up", "W")
    assert driver.held == {"up"}  # ↑ still down
    driver.release("up", "UP")
    assert driver.held == set()
