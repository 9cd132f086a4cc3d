"""DEM messages reach the event bus as they are logged (issue 11 item 3)."""

from __future__ import annotations

from pathlib import Path

from fieldtwin.plant import load_plant
from tests.tsx.dem24.helpers import unread_default_plant


def test_every_logged_dem_message_is_an_event_with_its_time_stamp(tmp_path: Path) -> None:
    # the default plant at max speed: a DEM 2412 in slot 4 with live inputs (without the
    # program's reading of the stack: tests/tsx/dem24/test_default_plant_stack.py has it)
    plant = load_plant(unread_default_plant(tmp_path), speed=None)
    try:
        sub = plant.events.subscribe(["dem"])
        plant.plc.advance(59.0)  # the time is set at the first sync pulse, at 60 s
        before = sub.take(10_000)
        plant.plc.advance(16.0)
        events = sub.take(10_000)
    finally:
        plant.close()
    assert before == []  # nothing is logged while the module has no time
    assert events, "no DEM message was published in 16 s of a pulsing input"
    assert {e.device for e in events} == {"4"}
    changes = [e for e in events if e.data["type"] == "change"]
    assert {e.data["channel"] for e in changes} >= {0}
    first = changes[0]
    assert str(first.data["stamp"]).startswith("1994-07-15 18:06:")
    assert first.data["state"] in (0, 1)
    assert all(e.data["stored"] for e in events)  # 16 s cannot fill a 200-message stack
    fills = [e.data["stack"] for e in events]
    assert fills == list(range(1, len(events) + 1))  # nobody reads the stack: one more each
    times = [e.t_us for e in events]
    assert times == sorted(times)


def test_a_message_that_finds_the_stack_full_is_an_event_saying_it_was_lost(
    tmp_path: Path,
) -> None:
    plant = load_plant(unread_default_plant(tmp_path), speed=None)
    try:
        dem = next(d for d in plant.devices if str(d.address) == "4")
        logbook = dem.dem.logbook  # type: ignore[attr-defined]
        sub = plant.events.subscribe(["dem"])
        plant.plc.advance(300.0)  # nobody reads the stack: 200 messages fill it
        events = sub.take(10_000)
    finally:
        plant.close()
    assert len(logbook.stack) == 200
    lost = [e for e in events if not e.data["stored"]]
    assert lost and all(e.data["stack"] == 200 for e in lost)
