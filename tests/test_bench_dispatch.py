"""``python -m rain_core.bench NAME``: the dispatcher refuses an unknown name and an output folder it cannot write
in, with a message and before any benchmark runs, and leaves help alone."""

from __future__ import annotations

import pytest

from rain_core.bench.__main__ import main, out_folder_problem


@pytest.mark.parametrize("argv", [["--out", "{bad}"], ["--quick", "--out={bad}"]])
def test_a_folder_that_cannot_be_made_is_refused_before_any_work(tmp_path, capsys, argv):
    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    args = [a.replace("{bad}", str(blocker / "out")) for a in argv]
    assert main(["physics", *args]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "cannot make it" in err and "Traceback" not in err
    assert not (tmp_path / "physics.md").exists()


def test_a_new_folder_is_made_with_its_parents_and_left_empty(tmp_path):
    folder = tmp_path / "a" / "b"
    assert out_folder_problem(["--quick", "--out", str(folder)]) is None
    assert folder.is_dir() and list(folder.iterdir()) == []  # the probe file is gone


def test_the_default_folder_is_checked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert out_folder_problem([]) is None and (tmp_path / "bench_out").is_dir()


def test_help_and_unknown_names_are_not_checked(tmp_path, capsys):
    blocker = tmp_path / "f"
    blocker.write_text("")
    with pytest.raises(SystemExit):
        main(["physics", "--help", "--out", str(blocker / "x")])
    assert "usage" in capsys.readouterr().out
    assert main(["nosuch", "--out", str(blocker / "x")]) == 2
    assert "unknown benchmark 'nosuch'" in capsys.readouterr().err


def test_a_name_too_long_is_said_as_the_command_line_says_it(tmp_path):
    problem = out_folder_problem(["--out", str(tmp_path / ("a" * 300))])
    assert problem is not None and "is 300 bytes long, at most 255 are allowed" in problem
    assert list(tmp_path.iterdir()) == []  # nothing made
