"""The README's Python API example runs as written, but for its frame size and step count (llvmpipe is slow)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_example() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    m = re.search(r"## Python API\n\n```python\n(.*?)```", text, re.S)
    assert m, "README.md has no '## Python API' section opening with a python block"
    return m.group(1)


def test_readme_example_runs():
    code = readme_example()
    small = code.replace("size=(320, 180)", "size=(64, 40)").replace("range(30)", "range(3)")
    assert small.count("size=(64, 40)") == 1 and small.count("range(3)") == 1, "the example changed: update me"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    result = subprocess.run([sys.executable, "-c", small], capture_output=True, text=True, timeout=300, cwd=ROOT,
                            env=env)
    assert result.returncode == 0, result.stderr
    first = result.stdout.splitlines()[0]
    assert first == "(40, 64, 3) (40, 64) ['class', 'glass_water', 'rain', 'road_water', 'spray']", result.stdout
