"""Where shaders/ and assets/ are, from the source tree or from an installed package."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

_REPO_ROOT = Path(__file__).resolve().parent.parent


def _locate(name: str) -> Path:
    in_tree = _REPO_ROOT / name
    if in_tree.is_dir():
        return in_tree
    # Installed wheel: pyproject maps the folder to the data package rain_core.<name>.
    return Path(str(resources.files(f"rain_core.{name}")))


SHADERS_DIR = _locate("shaders")
ASSETS_DIR = _locate("assets")
