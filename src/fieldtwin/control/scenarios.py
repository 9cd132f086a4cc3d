"""Scenarios on a running plant: ``POST /scenarios`` and what ``fieldtwin run --scenario``
and ``fieldtwin.testing.run_scenario`` need of the control API (docs/scenarios.md).

A scenario's steps are the control API's commands through the plant's door; where
nothing serves the door (no control API: ``--no-control``, a plant in a test),
:func:`fallback_handlers` gives the handlers of a Control made for the plant.
:class:`ScenarioRuns` keeps the scenarios the API started (the last MAX_KEPT).
"""

from __future__ import annotations

from collections import OrderedDict

from fieldtwin.control.resources import Conflict, Control, NotFound
from fieldtwin.control.sim import serve
from fieldtwin.errors import ConfigError
from fieldtwin.plant import Plant
from fieldtwin.runtime.door import CALL, LINE, Handler
from fieldtwin.runtime.runner import Runner
from fieldtwin.scenario import ScenarioRun, parse_scenario

MAX_KEPT = 64  # scenarios remembered for GET /scenarios/{id} (oldest forgotten first)
MAX_RUNNING = 8  # scenarios in progress at once


def _serves(plant: Plant, kind: str) -> bool:
    try:
        plant.door.handler(kind)
    except ConfigError:
        return False
    return True


def fallback_handlers(plant: Plant, runner: Runner | None = None) -> dict[str, Handler | None]:
    """For each command kind nothing serves on ``plant``'s door, the handler of a
    Control made for the plant (its own console for console lines); None where
    the door serves the kind already."""
    missing = [kind for kind in (CALL, LINE) if not _serves(plant, kind)]
    found: dict[str, Handler | None] = {CALL: None, LINE: None}
    if not missing:
        return found
    control = Control(plant, runner or Runner(plant.clock, None), plant.events)
    withdraw = serve(plant.door, control, control.console.handle)
    try:
        for kind in missing:
            found[kind] = plant.door.handler(kind)
    finally:
        withdraw()
    return found


class ScenarioRuns:
    """The scenarios started through the API, by id (on the simulation's thread only)."""

    def __init__(self, plant: Plant) -> None:
        self.plant = plant
        self._runs: OrderedDict[int, ScenarioRun] = OrderedDict()
        self._next = 1

    def start(self, text: str, name: str = "scenario") -> dict[str, object]:
        """Read ``text`` (a TOML scenario) and start it now; its id and state."""
        running = sum(1 for r in self._runs.values() if not r.result.done)
        if running >= MAX_RUNNING:
            raise Conflict(f"{running} scenarios are running (allowed at most {MAX_RUNNING})")
        handlers = fallback_handlers(self.plant)
        try:  # a text that fits the body's schema, not the scenario format or this plant
            scenario = parse_scenario(text, name)
            run = ScenarioRun(self.plant, scenario, call=handlers[CALL], line=handlers[LINE])
        except ConfigError as exc:
            raise Conflict(str(exc)) from None
        run.start()
        ident = self._next
        self._next += 1
        self._runs[ident] = run
        while len(self._runs) > MAX_KEPT:
            self._runs.popitem(last=False)
        return self.json(ident)

    def json(self, ident: int) -> dict[str, object]:
        run = self._runs.get(ident)
        if run is None:
            raise NotFound(f"no scenario {ident} (the last {MAX_KEPT} are kept)")
        return {"id": ident, **run.result.json()}

    def list(self) -> list[dict[str, object]]:
        return [
            {"id": i, "name": r.scenario.name, "done": r.result.done, "passed": r.result.passed}
            for i, r in self._runs.items()
        ]


__all__ = ["MAX_KEPT", "MAX_RUNNING", "ScenarioRuns", "fallback_handlers"]
