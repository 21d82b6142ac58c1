"""Output and input paths checked at the boundary, before any long work: every name at most NAME_MAX_BYTES long,
the whole path at most PATH_MAX_BYTES, a file not a folder (and the reverse), in a folder that exists and can be
written in. Each check returns why a path cannot be used, or None; the command line (app/cli.py), the sweeps
and the benchmarks' dispatcher turn that into their own error."""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

from rain_core.checks import quote

NAME_MAX_BYTES = 255  # longest file or folder name (one path component) on the usual file systems
PATH_MAX_BYTES = 4095  # longest whole path (Linux PATH_MAX less the terminating NUL)


def name_problem(path: Path) -> str | None:
    """Why ``path`` cannot be a file name on this system (too long), or None."""
    raw = os.fsencode(path)
    if len(raw) > PATH_MAX_BYTES:
        return f"the path is {len(raw)} bytes long, at most {PATH_MAX_BYTES} are allowed"
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > NAME_MAX_BYTES:
            return f"the name {quote(part)} is {size} bytes long, at most {NAME_MAX_BYTES} are allowed"
    return None


def probe_folder(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (missing, not a folder, not writable), or None.

    The check creates and removes a hidden temporary file: permission bits alone do not tell (root, read-only
    mounts, /proc).
    """
    try:
        if not folder.exists():
            return f"folder {folder} does not exist"
        if not folder.is_dir():
            return f"{folder} is not a folder"
        fd, probe = tempfile.mkstemp(prefix=".rainroad-check-", dir=folder)
    except OSError as exc:
        return f"cannot write in folder {folder}: {exc.strerror or exc}"
    os.close(fd)
    os.unlink(probe)
    return None


def check_output_file(path: Path, suffix: str = ".png") -> str | None:
    """Why a ``suffix`` file cannot be written at ``path``, or None. Creates nothing (a probe file is removed)."""
    if path.suffix.lower() != suffix:
        return f"must end in {suffix}, got {quote(str(path))}"
    problem = name_problem(path)
    if problem:
        return problem
    try:
        st = path.stat()
    except (FileNotFoundError, NotADirectoryError):  # the folder checks below say which
        st = None
    except OSError as exc:
        return f"cannot use {path}: {exc.strerror or exc}"
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            return f"{path} is a folder; name a {suffix} file"
        if not stat.S_ISREG(st.st_mode):
            return f"{path} exists and is not a regular file"
        try:
            with open(path, "ab"):  # opens for writing without changing the file
                pass
        except OSError as exc:
            return f"cannot write {path}: {exc.strerror or exc}"
        return None
    return probe_folder(path.parent)


def check_output_folder(folder: Path) -> str | None:
    """Why frames cannot be written into ``folder`` (created later if missing, in an existing folder), or None."""
    problem = name_problem(folder)
    if problem:
        return problem
    try:
        exists = folder.exists()
    except OSError as exc:
        return f"cannot use {folder}: {exc.strerror or exc}"
    if exists and not folder.is_dir():
        return f"{folder} exists and is not a folder"
    return probe_folder(folder if exists else folder.parent)


def check_input_file(path: Path) -> str | None:
    """Why ``path`` cannot be read as a file, or None."""
    problem = name_problem(path)
    if problem:
        return problem
    try:
        if not path.is_file():
            return f"no such file: {path}" if not path.exists() else f"{path} is not a file"
    except OSError as exc:
        return f"cannot read {path}: {exc.strerror or exc}"
    return None
