"""The Rain Manager's benchmark (``python -m rain_core.bench panel``): the panel drawn over a heavy-rain frame in
each of its states, its CPU ms outside GL, GL calls and uploads, and the tables it writes."""

from __future__ import annotations

import json

import pytest

from rain_core.bench.panel import STATES, main, measure_state, parse_args

SIZE = (640, 360)


@pytest.mark.parametrize("state, headers", [("hidden", 0), ("rain", 1)])
def test_a_state_opens_its_headers_and_draws_them(gl_ctx, state, headers):
    result = measure_state(gl_ctx, state, SIZE, frames=2, warmup=2)
    assert result["state"] == state and len(result["sections"]) == headers
    assert result["cpu_ms"] > 0.0 and result["cpu_ms_all"] >= result["cpu_ms"]
    if headers:  # a visible panel is drawn with GL: its vertices uploaded, its draws made
        assert result["gl_calls"] > 0 and result["upload_kb"] > 0.0
    else:  # hidden: nothing to draw
        assert result["gl_calls"] == 0 and result["upload_kb"] == 0.0


def test_every_section_opens_each_header(gl_ctx):
    result = measure_state(gl_ctx, "every section", SIZE, frames=1, warmup=1)
    assert {"Rain", "Performance"} <= set(result["sections"]) and len(result["sections"]) > 10


def test_main_writes_its_tables(tmp_path, capsys):
    assert main(["--quick", "--size", "320x240", "--out", str(tmp_path)]) == 0
    rows = json.loads((tmp_path / "panel.json").read_text())
    assert [r["state"] for r in rows] == list(STATES)
    text = (tmp_path / "panel.md").read_text()
    assert "CPU ms outside GL" in text and "every section" in text
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("argv, flag", [(["--frames", "0"], "--frames"), (["--warmup", "-1"], "--warmup"),
                                        (["--size", "0x5"], "--size")])
def test_bad_flags_name_the_flag(argv, flag, capsys):
    with pytest.raises(SystemExit):
        parse_args(argv)
    assert flag in capsys.readouterr().err


def test_an_unknown_state_is_refused(gl_ctx):
    with pytest.raises(ValueError, match="state must be one of"):
        measure_state(gl_ctx, "open", SIZE)
