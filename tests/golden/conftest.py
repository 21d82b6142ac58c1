"""``--update-golden``: rewrite the stored golden PNGs from the current code instead of comparing with them."""

from __future__ import annotations

import pytest


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true", default=False,
                     help="rewrite tests/golden/*.png from the current code (after an intended change)")


@pytest.fixture(scope="session")
def update_golden(request) -> bool:
    # getoption's default: this conftest's hook only runs when tests/golden is on the command line.
    return bool(request.config.getoption("--update-golden", default=False))
