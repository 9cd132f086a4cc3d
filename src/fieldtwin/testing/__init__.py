"""fieldtwin for test authors: time helpers, assertions, a running plant, a pytest plugin.

The pytest plugin (``fieldtwin.testing.plugin``, entry point ``pytest11``) gives the
fixtures ``plant``, ``plc``, ``tes``, ``running_plant``, ``advance_to`` and
``run_until`` and the marker ``plant``; the functions here work on any Plant, Plc,
Tes or RunningPlant, with or without pytest (docs/testing.md).
"""

from fieldtwin.testing.helpers import (
    NotWithin,
    advance_to,
    assert_leds,
    assert_object,
    assert_state,
    run_until,
)
from fieldtwin.testing.process import Endpoint, PlantStartError, RunningPlant, start_plant
from fieldtwin.testing.scenarios import run_scenario

__all__ = [
    "Endpoint",
    "NotWithin",
    "PlantStartError",
    "RunningPlant",
    "advance_to",
    "assert_leds",
    "assert_object",
    "assert_state",
    "run_scenario",
    "run_until",
    "start_plant",
]
