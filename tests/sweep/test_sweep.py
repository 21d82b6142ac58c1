"""Sweeps: a small grid completes on the local pool (and under Ray where it is installed), byte-identical between
backends and worker counts; a killed sweep resumes to the same manifest; a failing sequence is reported and the
rest completes; bad sweep files fail before rendering, naming the key."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rain_core.session import load_dataset
from rain_core.sweep import Job, SweepError, load_manifest, load_sweep, run_sweep
from rain_core.sweep.sequence import folder_checksum

ROOT = Path(__file__).resolve().parents[2]
SWEEP = """
[sweep]
seconds = 0.2
fps = 10
size = "48x32"
camera = "{camera}"
labels = {labels}

[grid]
"rain.rate_mm_h" = [2.0, 16.0]
seed = [1, 2]
"""


def _spec(tmp_path, camera="driver", labels="true", extra=""):
    path = tmp_path / "sweep.toml"
    path.write_text(SWEEP.format(camera=camera, labels=labels) + extra, encoding="utf-8")
    return load_sweep(path)


def _stable(lines):
    return [{k: v for k, v in line.items() if k != "seconds"} for line in lines]


def test_grid_completes_with_labels_and_a_manifest(tmp_path):
    spec = _spec(tmp_path)
    assert len(spec.jobs) == 4 and spec.frames == 2
    lines = run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    assert [line["status"] for line in lines] == ["complete"] * 4
    manifest = load_manifest(tmp_path / "out")
    assert set(manifest) == {job.id for job in spec.jobs}
    for job, line in zip(spec.jobs, lines, strict=True):
        folder = tmp_path / "out" / job.id
        assert line["frames"] == 2 and line["checksum"] == folder_checksum(folder)
        assert line["params"] == dict(job.params) and line["seed"] == job.seed
        assert (folder / "settings.toml").is_file() and len(load_dataset(folder)) == 2
    # The rate is in the resolved settings and in the labels.
    labels = load_dataset(tmp_path / "out" / spec.jobs[-1].id).labels(0)
    assert labels["rain_mm_h"] == 16.0 and labels["seed"] == 2
    # A rerun finds everything done and renders nothing.
    t0 = time.perf_counter()
    again = run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    assert _stable(again) == _stable(lines) and time.perf_counter() - t0 < 5.0


def test_same_bytes_with_one_or_two_workers(tmp_path):
    spec = _spec(tmp_path, labels="false")
    one = run_sweep(spec, tmp_path / "one", workers=1, progress=False)
    two = run_sweep(spec, tmp_path / "two", workers=2, progress=False)
    assert [x["checksum"] for x in one] == [x["checksum"] for x in two]


def test_a_failing_sequence_is_reported_and_the_rest_completes(tmp_path):
    spec = _spec(tmp_path, labels="false")
    spec.jobs.append(Job(len(spec.jobs), (("rain.rate_mm_h", -1.0),), 1))  # slipped past the checks
    lines = run_sweep(spec, tmp_path / "out", workers=2, progress=False)
    assert [line["status"] for line in lines] == ["complete"] * 4 + ["failed"]
    assert "rain.rate_mm_h" in lines[-1]["error"] and not (tmp_path / "out" / spec.jobs[-1].id).exists()
    assert not list((tmp_path / "out").glob(".tmp-*"))


def _cli(tmp_path, *extra, **popen):
    return subprocess.Popen([sys.executable, "-m", "app", "sweep", str(tmp_path / "sweep.toml"), "--out",
                             str(tmp_path / "out"), "--workers", "1", *extra], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)


@pytest.mark.parametrize("how", ["kill", "interrupt"])
def test_a_stopped_sweep_resumes_to_the_same_manifest(tmp_path, how):
    spec = _spec(tmp_path, labels="false")
    reference = run_sweep(spec, tmp_path / "reference", workers=1, progress=False)
    proc = _cli(tmp_path, start_new_session=True)
    manifest = tmp_path / "out" / "manifest.jsonl"
    deadline = time.time() + 120
    while time.time() < deadline:  # stop it once the first sequence is in the manifest
        if manifest.is_file() and '"complete"' in manifest.read_text():
            break
        time.sleep(0.05)
    if how == "kill":
        os.killpg(proc.pid, signal.SIGKILL)
    else:
        os.killpg(proc.pid, signal.SIGINT)
    code = proc.wait(timeout=120)
    if how == "interrupt":
        assert code == 130
    lines = [json.loads(t) for t in manifest.read_text().splitlines()]  # consistent: every line parses
    done = [line for line in lines if line["status"] == "complete"]
    assert 1 <= len(done) and all(folder_checksum(tmp_path / "out" / d["id"]) == d["checksum"] for d in done)
    resumed = _cli(tmp_path)
    out, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    assert _stable(load_manifest(tmp_path / "out").values()) == _stable(reference)


def test_under_ray_the_same_bytes(tmp_path):
    ray = pytest.importorskip("ray", reason='Ray is not installed (pip install -e ".[scale]")')
    spec = _spec(tmp_path, labels="false")
    pool = run_sweep(spec, tmp_path / "pool", workers=2, progress=False)
    try:
        on_ray = run_sweep(spec, tmp_path / "ray", workers=2, ray_address="local", progress=False)
    finally:
        if ray.is_initialized():
            ray.shutdown()
    assert [x["status"] for x in on_ray] == ["complete"] * 4
    assert [x["checksum"] for x in on_ray] == [x["checksum"] for x in pool]


@pytest.mark.parametrize("extra,match", [
    ('\n[[runs]]\n"rain.rate_mm_h" = -3\n', r"\[\[runs\]\] #1 'rain.rate_mm_h'.*\[0, 500\]"),
    ('\n[[runs]]\n"rain.nope" = 1\n', "not a settings path"),
    ('\n[[runs]]\nseed = -1\n', r"seed: must be an integer in \[0, 2147483647\]"),
])
def test_bad_values_fail_before_rendering(tmp_path, extra, match):
    with pytest.raises(SweepError, match=match):
        _spec(tmp_path, extra=extra)


@pytest.mark.parametrize("camera,match", [("drone", "camera: must be one of driver, chase")])
def test_bad_sweep_keys(tmp_path, camera, match):
    with pytest.raises(SweepError, match=match):
        _spec(tmp_path, camera=camera)
    (tmp_path / "bad.toml").write_text('[sweep]\nsize = "10x10"\n')
    with pytest.raises(SweepError, match=r"size: each side must be in \[16, 8192\] px"):
        load_sweep(tmp_path / "bad.toml")
    (tmp_path / "worse.toml").write_text("[sweep\n")
    with pytest.raises(SweepError, match="not valid TOML"):
        load_sweep(tmp_path / "worse.toml")


def test_cli_bad_input_exits_2(tmp_path):
    (tmp_path / "sweep.toml").write_text('[sweep]\nfps = 0\n')
    proc = _cli(tmp_path)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2 and "[sweep] fps" in err
