"""Hypothesis profiles for the reliability suite: ``ci`` (the default: fast, derandomized, so a CI run is
reproducible) and ``long`` (many random examples; ``HYPOTHESIS_PROFILE=long python -m pytest tests/reliability``).
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile("ci", max_examples=25, deadline=None, derandomize=True, database=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("long", max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
