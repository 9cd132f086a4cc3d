"""Scenarios: a timeline of steps at simulated times and expectations (docs/scenarios.md).

``read_scenario(path)`` reads and checks a TOML scenario file; ``ScenarioRun`` runs
one on a plant, each step through the plant's door at its simulated instant.  The
surfaces: ``fieldtwin run PLANT --scenario FILE``, ``POST /scenarios``, the
console's ``scenario FILE``, ``fieldtwin.testing.run_scenario``.
"""

from fieldtwin.scenario.run import Outcome, ScenarioResult, ScenarioRun
from fieldtwin.scenario.spec import (
    MAX_AT_S,
    MAX_ENTRIES,
    Expect,
    Scenario,
    Step,
    parse_scenario,
    read_scenario,
    scenario_of,
)

__all__ = [
    "MAX_AT_S",
    "MAX_ENTRIES",
    "Expect",
    "Outcome",
    "Scenario",
    "ScenarioResult",
    "ScenarioRun",
    "Step",
    "parse_scenario",
    "read_scenario",
    "scenario_of",
]
