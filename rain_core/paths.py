"""Where shaders/ and assets/ are, from an installed package or from the source tree."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
_REPO_ROOT = _PACKAGE.parent


def _locate(name: str) -> Path:
    # Installed wheel: pyproject maps the top-level folder into the package as rain_core/<name>.
    installed = _PACKAGE / name
    if installed.is_dir():
        return installed
    # Source tree (and editable installs): the folder sits beside rain_core/.
    return _REPO_ROOT / name


SHADERS_DIR = _locate("shaders")
ASSETS_DIR = _locate("assets")
