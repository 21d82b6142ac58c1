"""OpenSCENARIO weather in and out: ``load(path) -> Settings`` reads the first ``Environment`` of a scenario's
``Init`` (inline or from a catalog; OpenSCENARIO 1.0–1.3), ``save(settings, path)`` writes a minimal valid 1.2
file whose ``Environment`` reproduces the weather. Conventions: ``rain_core.openscenario.mapping``."""

from rain_core.openscenario.reader import OpenScenarioError, load
from rain_core.openscenario.writer import save

__all__ = ["OpenScenarioError", "load", "save"]
