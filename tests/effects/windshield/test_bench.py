"""The windshield benchmark's frame case (``python -m rain_core.bench windshield --frame-case``): it runs, and the
compiled kernels and their NumPy twins end on the same glass (its state digest) from the frame benchmark's full,
auto-wiped glass."""

import pytest

from rain_core import jit
from rain_core.bench import windshield as bench


def test_frame_case_runs_and_writes_its_table(tmp_path, capsys):
    assert bench.main(["--frame-case", "--quick", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "windshield.md").read_text()
    assert "Frame-benchmark glass" in text and "state digest" in text


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")
def test_frame_case_is_the_same_glass_with_the_kernels_and_their_twins():
    digests = []
    for on in (False, True):
        with jit.forced(on):
            n0, mean_n, *_, digest = bench.frame_case(20)
            digests.append(digest)
    assert n0 > 5000 and mean_n > 5000
    assert digests[0] == digests[1]
