"""An installed (non-editable) rainroad must carry its shaders and assets inside the package."""

import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_wheel_contains_shaders_and_assets(tmp_path):
    result = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
                             "-w", str(tmp_path), str(ROOT)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    wheel = next(tmp_path.glob("rainroad-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    for shader in (ROOT / "shaders").rglob("*"):
        if shader.is_file():
            assert f"rain_core/shaders/{shader.relative_to(ROOT / 'shaders').as_posix()}" in names
    assert "rain_core/assets/scenarios/heavy.toml" in names
    assert "app/__main__.py" in names
    assert any(n.endswith("entry_points.txt") for n in names)
    for source in [*(ROOT / "rain_core").rglob("*.py"), *(ROOT / "app").rglob("*.py")]:
        name = source.relative_to(ROOT).as_posix()
        assert name in names, f"{name} is missing from the wheel: list its package in pyproject.toml"
