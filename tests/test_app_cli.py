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


# --- issue 18: every bad command line is answered before any rendering, exit 2 naming the flag -------------


def parse_error(argv, capsys):
    """Exit code and stderr of parse_args + settings_from_args on ``argv`` (in process: nothing renders)."""
    from app.__main__ import settings_from_args
    from app.cli import parse_args

    with pytest.raises(SystemExit) as exc:
        settings_from_args(parse_args(argv))
    return exc.value.code, capsys.readouterr().err


LONG_NAME = "a" * 256  # one byte over NAME_MAX


@pytest.mark.parametrize("flag, value, fragment", [
    ("--screenshot", "{tmp}/folder.png", "is a folder"),
    ("--screenshot", "/proc/x.png", "cannot write"),
    ("--screenshot", "{tmp}/missing/x.png", "does not exist"),
    ("--screenshot", "{tmp}/file.txt/x.png", "not a folder"),
    ("--screenshot", "{tmp}/" + LONG_NAME + ".png", "at most 255"),
    ("--screenshot", "", "must not be empty"),
    ("--record", "{tmp}/file.txt", "not a folder"),
    ("--record", "/proc/rec", "cannot write"),
    ("--record", "{tmp}/missing/rec", "does not exist"),
    ("--record", "{tmp}/" + LONG_NAME, "at most 255"),
    ("--record", "", "must not be empty"),
    ("--record", "  ", "must not be empty"),
    ("--scenario", "{tmp}/" + LONG_NAME + ".toml", "at most 255"),
    ("--scenario", "{tmp}/folder.png", "not a file"),
    ("--scenario", "x" * 5000, "bytes long"),
])
def test_bad_paths_exit_2_before_rendering(tmp_path, capsys, flag, value, fragment):
    (tmp_path / "folder.png").mkdir()
    (tmp_path / "file.txt").write_text("x")
    before = sorted(tmp_path.rglob("*"))
    code, err = parse_error(["--headless", flag, value.format(tmp=tmp_path)], capsys)
    assert code == 2 and f"argument {flag}" in err and fragment in err, err
    assert len(err.splitlines()[-1]) < 300 + len(str(tmp_path))  # a long name is quoted cut, not repeated
    assert sorted(tmp_path.rglob("*")) == before  # nothing created (the write probe is removed)


@pytest.mark.skipif(not hasattr(__import__("os"), "geteuid") or __import__("os").geteuid() == 0,
                    reason="root writes into read-only folders")
def test_unwritable_folder_exits_2(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    for flag, value in (("--screenshot", locked / "x.png"), ("--record", locked / "rec")):
        code, err = parse_error(["--headless", flag, str(value)], capsys)
        assert code == 2 and flag in err and "cannot write" in err


def test_good_paths_pass_and_create_nothing(tmp_path):
    from app.cli import parse_args

    args = parse_args(["--headless", "--screenshot", str(tmp_path / "x.PNG"), "--record", str(tmp_path / "rec")])
    assert args.screenshot.name == "x.PNG" and args.record.name == "rec"
    assert list(tmp_path.iterdir()) == []  # the record folder is made when the run starts


@pytest.mark.parametrize("argv", [
    ["--seconds", "-inf"], ["--seconds=-inf"], ["--seconds", "nan"], ["--seconds=nan"], ["--seconds", "-nan"],
    ["--seconds", "-1"], ["--seconds", "-1e3"], ["--seconds", "inf"], ["--seconds", "1e400"], ["--seconds", "86401"],
    ["--seconds", "9" * 500],
])
def test_seconds_out_of_range_names_the_flag_and_range(capsys, argv):
    code, err = parse_error(["--headless", *argv], capsys)
    assert code == 2 and "argument --seconds" in err and "[0, 86400] s" in err, err
    assert "expected one argument" not in err


def test_negative_values_reach_every_flag_s_range_check(capsys):
    for argv, fragment in ((["--fps", "-inf"], "[1, 240]"), (["--hour", "-0.5"], "[0, 24]"),
                           (["--rain-rate", "-inf"], "[0, 500]"), (["--traffic", "-3"], "[0, 20]"),
                           (["--seed", "-1"], "[0, 2147483647]")):
        code, err = parse_error(["--headless", *argv], capsys)
        assert code == 2 and f"argument {argv[0]}" in err and fragment in err, err


@pytest.mark.parametrize("argv, flag", [
    (["--size", "١٦x١٦"], "--size"),  # Arabic-Indic digits
    (["--size", "１６x16"], "--size"),  # full-width digits
    (["--size", "16x16x16"], "--size"),
    (["--size", "16*16"], "--size"),
    (["--size", "9" * 5000 + "x16"], "--size"),
    (["--seconds", "٣"], "--seconds"),
    (["--seconds", "1_0"], "--seconds"),
    (["--seed", "٣"], "--seed"),
    (["--seed", "1_000"], "--seed"),
    (["--seed", "9" * 5000], "--seed"),
    (["--traffic", "2.0"], "--traffic"),
])
def test_numbers_are_ascii_only(capsys, argv, flag):
    code, err = parse_error(["--headless", *argv], capsys)
    assert code == 2 and f"argument {flag}" in err and len(err.splitlines()[-1]) < 300, err


def test_accepted_forms_are_documented_and_consistent(capsys):
    from app.cli import parse_args

    assert parse_args(["--size", "16X16"]).size == parse_args(["--size", "16x16"]).size == (16, 16)
    assert parse_args(["--seconds", " 2e1 "]).seconds == 20.0 and parse_args(["--seed", "+7"]).seed == 7
    with pytest.raises(SystemExit):
        parse_args(["--help"])
    text = capsys.readouterr().out
    assert "ASCII digits" in text and "'x' or 'X'" in text and "255 bytes" in text
    assert "[0, 86400] s" in text


def test_long_runs_announce_frames_and_an_estimate():
    from app.headless import LONG_RUN_FRAMES, describe_duration, frame_count, plan_line

    assert frame_count(1e3, 30.0) == 30_000 > LONG_RUN_FRAMES and frame_count(0.0, 30.0) == 1
    line = plan_line(30_000, 30.0, (1280, 720), 0.25)
    assert "30000 frames" in line and "1000 s at 30 frames/s" in line and "about 2 h 5 min" in line
    assert "\n" not in line
    assert describe_duration(59.6) == "1 min 0 s" and describe_duration(3) == "3 s"


# --- issue 15: --record FILE.mp4 and --labels are checked before any rendering ---------------------------


@pytest.mark.parametrize("argv, fragment", [
    (["--record", "{tmp}/folder.mp4"], "is a folder; name a .mp4 file"),
    (["--record", "{tmp}/missing/out.mp4"], "does not exist"),
    (["--record", "{tmp}/file.txt/out.mp4"], "not a folder"),
    (["--record", "{tmp}/" + "a" * 252 + ".mp4"], "at most 255"),
    (["--record", "/proc/out.mp4"], "cannot write"),
    (["--record", "{tmp}/out.mp4", "--size", "65x48"], "even width and height"),
    (["--record", "{tmp}/taken.mp4", "--labels"], "not a folder"),  # taken.labels is a file
])
def test_bad_video_paths_exit_2_before_rendering(tmp_path, capsys, argv, fragment):
    pytest.importorskip("av", reason="PyAV not installed: the .mp4 checks start with it")
    (tmp_path / "folder.mp4").mkdir()
    (tmp_path / "file.txt").write_text("x")
    (tmp_path / "taken.labels").write_text("x")
    before = sorted(tmp_path.rglob("*"))
    code, err = parse_error(["--headless", *(a.format(tmp=tmp_path) for a in argv)], capsys)
    assert code == 2 and "argument --record" in err and fragment in err, err
    assert sorted(tmp_path.rglob("*")) == before


def test_mp4_without_pyav_exits_2_naming_the_flag_and_the_install(tmp_path, capsys, monkeypatch):
    import app.recording

    monkeypatch.setattr(app.recording, "have_pyav", lambda: False)
    code, err = parse_error(["--headless", "--record", str(tmp_path / "out.mp4")], capsys)
    assert code == 2 and "argument --record" in err and "PyAV" in err and "pip install 'rainroad[video]'" in err
    assert list(tmp_path.iterdir()) == []


def test_labels_need_record(capsys, tmp_path):
    code, err = parse_error(["--headless", "--labels"], capsys)
    assert code == 2 and "argument --labels: only with --record" in err
    code, err = parse_error(["--labels", "--record", str(tmp_path / "r")], capsys)
    assert code == 2 and "only with --headless" in err


def test_good_video_paths_pass_and_create_nothing(tmp_path):
    pytest.importorskip("av", reason="PyAV not installed: the .mp4 checks start with it")
    from app.cli import parse_args

    args = parse_args(["--headless", "--record", str(tmp_path / "out.MP4"), "--labels", "--size", "64x48"])
    assert args.labels and args.record.name == "out.MP4"
    assert list(tmp_path.iterdir()) == []


def test_headless_mp4_decodes_to_n_frames(tmp_path):
    av = pytest.importorskip("av", reason="PyAV not installed (pip install 'rainroad[video]')")
    out = tmp_path / "out.mp4"
    result = run_app("--headless", "--size", "64x48", "--seconds", "0.4", "--fps", "10", "--traffic", "0",
                     "--record", str(out))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # not a terminal: no progress lines in logs
    with av.open(str(out)) as container:
        assert sum(1 for _ in container.decode(video=0)) == 4


def test_quality_and_subframes_are_checked(capsys):
    from app.cli import parse_args

    for argv, fragment in ((["--quality", "best"], "argument --quality: invalid choice"),
                           (["--subframes", "0"], "argument --subframes: must be in [1, 256]"),
                           (["--subframes", "2.5"], "argument --subframes")):
        code, err = parse_error(["--headless", *argv], capsys)
        assert code == 2 and fragment in err, err
    args = parse_args(["--headless", "--quality", "offline", "--subframes", "8"])
    assert args.quality == "offline" and args.subframes == 8
