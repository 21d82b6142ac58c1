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


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")
def test_frame_case_kernel_table_accounts_for_the_step_and_restores_the_kernels():
    from rain_core.effects.windshield import kernels

    before = {name: getattr(kernels, name) for name in ("merge_drops", "move_drops", "sort_rows")}
    with jit.forced(True):
        table, step_us, slid, merged, boxed = bench.frame_case_kernels(10)
    assert {name: getattr(kernels, name) for name in before} == before  # the timers are gone again
    names = [row[0] for row in table]
    # The step's passes over the drops: each called once a step, through the package the fast path calls.
    for name in ("move_drops", "merge_drops", "shed_rows", "sort_rows"):
        assert name in names and table[names.index(name)][1] >= 1
    assert names[-1].startswith("(Python")
    # kernels + the rest = the step (each figure rounded to 0.1 µs)
    assert sum(row[2] for row in table) == pytest.approx(step_us, abs=0.05 * len(table))
    assert all(row[2] >= 0.0 for row in table[:-1]) and step_us > 0.0
    assert slid > 0 and merged > 0  # at 100 km/h drops slide and merge every step
    assert 0.0 <= boxed <= 1.0


def test_frame_case_kernel_table_is_empty_without_the_kernels():
    with jit.forced(False):
        table, step_us, slid, merged, boxed = bench.frame_case_kernels(3)
    assert table == [] and step_us > 0.0 and slid == 0.0 and boxed == 0.0
