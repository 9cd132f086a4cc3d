"""``run_scenario``: a scenario file (docs/scenarios.md) run on a test's plant.

On the ``plant`` fixture (an in-process Plant) the steps go through the plant's
door to the control API's own commands (a Control made for the plant when no
control API serves it) and simulated time runs to the scenario's end at once;
on the ``running_plant`` fixture (a real ``fieldtwin run``) the scenario is
started with ``POST /scenarios`` and its result awaited (bounded by ``wall_s``).
A failure raises AssertionError with the first failure's message (the table, the
object, expected and actual values, the simulated time); ``check=False`` returns
the result instead.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fieldtwin.control.scenarios import fallback_handlers
from fieldtwin.plant import Plant
from fieldtwin.runtime.door import CALL, LINE
from fieldtwin.scenario import ScenarioRun, read_scenario
from fieldtwin.testing.process import DEFAULT_SCENARIO_WALL_S as DEFAULT_WALL_S
from fieldtwin.testing.process import RunningPlant
from fieldtwin.testing.targets import PlantTarget


def run_scenario(
    target: Plant | RunningPlant,
    path: str | Path,
    *,
    check: bool = True,
    wall_s: float = DEFAULT_WALL_S,
) -> dict[str, Any]:
    """Run the scenario file ``path`` on ``target`` from its simulated time now; its
    result (``passed``, ``failure``, ``outcomes``: docs/scenarios.md)."""
    __tracebackhide__ = True
    if isinstance(target, RunningPlant):
        result = target.scenario(Path(path), wall_s)
    elif isinstance(target, Plant):
        result = _in_process(target, Path(path))
    else:
        raise TypeError(f"run_scenario: a Plant or a RunningPlant, not {type(target).__name__}")
    if check and not result["passed"]:
        raise AssertionError(str(result["failure"] or f"scenario {path} did not end"))
    return result


def _in_process(plant: Plant, path: Path) -> dict[str, Any]:
    scenario = read_scenario(path)
    fallback = fallback_handlers(plant)
    run = ScenarioRun(plant, scenario, call=fallback[CALL], line=fallback[LINE])
    run.start()
    try:
        PlantTarget(plant).advance_to(run.end_us / 1e6)
    finally:
        run.cancel()
    return run.result.json()


__all__ = ["DEFAULT_WALL_S", "run_scenario"]
