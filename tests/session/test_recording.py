"""Recording (issue 15): MP4 of N frames decodes to N, interrupted runs stay valid, labels on disk, progress."""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

SIZE = (64, 48)  # even: H.264 (yuv420p) needs it


def need_av():
    return pytest.importorskip("av", reason="PyAV not installed (pip install 'rainroad[video]'): no MP4 tests")


def decoded_frames(path) -> list[np.ndarray]:
    av = need_av()
    with av.open(str(path)) as container:
        return [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]


def run_args(tmp_path, record, seconds=0.3, labels=False, **extra):
    return SimpleNamespace(size=SIZE, seed=1, fps=10.0, seconds=seconds, record=record, labels=labels,
                           screenshot=None, panel=False, **extra)


def test_video_recorder_writes_n_frames_that_decode(tmp_path):
    need_av()
    from app.recording import VideoRecorder

    rng = np.random.default_rng(1)
    images = [np.full((SIZE[1], SIZE[0], 3), 40 * i, np.uint8) + rng.integers(0, 8, (48, 64, 3), dtype=np.uint8)
              for i in range(5)]
    rec = VideoRecorder(tmp_path / "a.mp4", 30.0, SIZE)
    for img in images:
        rec.add(img)
    rec.close()
    rec.close()
    got = decoded_frames(tmp_path / "a.mp4")
    assert len(got) == 5 and got[0].shape == (48, 64, 3)
    for a, b in zip(got, images, strict=True):  # H.264 at CRF 18: close, not exact
        assert np.abs(a.astype(int) - b.astype(int)).mean() < 6.0
    with pytest.raises(ValueError, match="even width and height"):
        VideoRecorder(tmp_path / "b.mp4", 30.0, (63, 48))


def cheap_settings():
    from rain_core.settings import Settings, set_value

    s = Settings()
    for key, value in {"quality.ripple_grid": 64, "quality.windshield_resolution": 128, "spray.budget": 3000,
                       "windshield.drop_budget": 1000, "traffic.count": 1}.items():
        set_value(s, key, value)
    return s


def test_headless_mp4_with_labels_round_trip(tmp_path, capsys):
    need_av()
    pytest.importorskip("rain_core.labels", reason="the label images come from rain_core.labels")
    from app.headless import run_headless
    from rain_core.session import load_dataset

    out = tmp_path / "out.mp4"
    assert run_headless(run_args(tmp_path, out, seconds=0.3, labels=True), cheap_settings()) == 0
    assert "wrote 3 frames" in capsys.readouterr().out
    frames = decoded_frames(out)
    assert len(frames) == 3
    ds = load_dataset(tmp_path / "out.labels")
    assert len(ds) == 3 and ds.header["size"] == list(SIZE) and ds.header["video"] == "../out.mp4"
    caps = list(ds)
    assert [c.labels["frame"] for c in caps] == [1, 2, 3]
    assert np.array_equal(caps[2].rgb, frames[2]) and caps[2].depth_m.shape == (48, 64)
    assert caps[0].labels["camera_intrinsics"].shape == (3, 3) and "sky" in caps[0].labels["class_ids"]
    assert set(caps[0].masks) == {"rain", "glass_water", "road_water", "spray", "class"}


def test_png_folder_with_labels_round_trip(tmp_path):
    pytest.importorskip("rain_core.labels", reason="the label images come from rain_core.labels")
    from app.headless import run_headless
    from rain_core.session import load_dataset

    rec = tmp_path / "rec"
    assert run_headless(run_args(tmp_path, rec, seconds=0.2, labels=True), cheap_settings()) == 0
    names = sorted(p.name for p in rec.iterdir())
    assert names == ["dataset.json", "frame_00000.npz", "frame_00000.png", "frame_00001.npz", "frame_00001.png",
                     "labels.jsonl"]
    ds = load_dataset(rec)
    cap = ds[-1]
    assert cap.rgb.shape == (48, 64, 3) and cap.labels["frame"] == 2 and ds.header["video"] is None
    # A line cut short by a crash is skipped, the frames before it load.
    with open(rec / "labels.jsonl", "a") as f:
        f.write('{"rain_mm_h": 2.0, "wetn')
    assert len(load_dataset(rec)) == 2
    with pytest.raises(ValueError, match="not a rainroad labels folder"):
        load_dataset(tmp_path)


def test_an_error_mid_run_finalises_the_video(tmp_path, monkeypatch, capsys):
    need_av()
    from app.headless import run_headless
    from rain_core.session import Session

    calls = {"n": 0}
    step = Session.step

    def failing_step(self, dt_s, drive=None, subframes=1, draw=True):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        step(self, dt_s, drive, subframes, draw)

    monkeypatch.setattr(Session, "step", failing_step)
    out = tmp_path / "cut.mp4"
    assert run_headless(run_args(tmp_path, out, seconds=10.0), cheap_settings()) == 130
    assert "stopped after 3 of 100 frames" in capsys.readouterr().err
    assert len(decoded_frames(out)) == 3

    calls["n"] = 0
    def boom(self, dt_s, drive=None, subframes=1, draw=True):
        raise RuntimeError("boom")

    monkeypatch.setattr(Session, "step", boom)
    with pytest.raises(RuntimeError, match="boom"):
        run_headless(run_args(tmp_path, tmp_path / "none.mp4", seconds=1.0), cheap_settings())
    assert not (tmp_path / "none.mp4").exists()  # no frame: no file (the header is written with the first frame)


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_keeps_a_decodable_video(tmp_path):
    need_av()
    out = tmp_path / "run.mp4"
    proc = subprocess.Popen([sys.executable, "-m", "app", "--headless", "--size", "64x48", "--seconds", "600",
                             "--fps", "10", "--traffic", "0", "--record", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (out.exists() and out.stat().st_size > 0) and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)  # the container header is written when the first frame is encoded
    time.sleep(3.0)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "stopped after" in stderr and "Traceback" not in stderr
    written = int(stdout.split("wrote ")[1].split()[0])
    assert written > 0 and len(decoded_frames(out)) == written


def test_progress_only_on_a_terminal():
    from app.recording import Progress

    class Tty(io.StringIO):
        def isatty(self):
            return True

    now = [0.0]
    quiet = io.StringIO()
    p = Progress(10, stream=quiet, clock=lambda: now[0])
    for i in range(10):
        now[0] += 1.0
        p.update(i + 1)
    p.finish()
    assert quiet.getvalue() == ""
    tty = Tty()
    now[0] = 0.0
    p = Progress(10, stream=tty, clock=lambda: now[0])
    now[0] = 4.0
    p.update(2)
    assert p.line(2, 4.0) == "rainroad: frame 2/10, 0.50 frames/s, about 16 s left"
    p.finish()
    assert tty.getvalue() == "\r\x1b[K" + p.line(2, 4.0) + "\n"


def test_offline_bench_error_measure():
    from rain_core.bench.offline import SUBFRAMES, errors

    a = [np.zeros((2, 2, 3), np.uint8)]
    assert SUBFRAMES[0] == 1 and SUBFRAMES[-1] == 64
    assert errors(a, a) == (0.0, float("inf"))
    mae, psnr = errors([np.full((2, 2, 3), 10, np.uint8)], a)
    assert mae == 10.0 and psnr == pytest.approx(20 * np.log10(25.5))
