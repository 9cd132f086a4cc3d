"""Every (state, input) pair of every DEM state-machine table (DESIGN rules 4 and 12).

For each table a real owner is built, forced into the state, and given the input: it
ends in the table's target, or the machine raises a ProtocolError naming the machine,
the state and the input and stays where it was.  Hypothesis varies the owner (time,
fault, pending reference, modification indicator, drift) around each pair.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.errors import ProtocolError
from fieldtwin.fsm import Machine, Table, tables
from fieldtwin.tsx.dem24.civil import CivilTime
from fieldtwin.tsx.dem24.oscillation import OSCILLATION, Detector, Thresholds
from fieldtwin.tsx.dem24.syncinput import SYNC_INPUT, SyncLevel
from fieldtwin.tsx.dem24.timebase import TIMEBASE, Timebase, TimeReference, TimeState
from tests.tsx.dem24.helpers import make

Owner = Callable[[enum.Enum, st.DataObject], tuple[Machine[Any, Any, Any], int]]


def _timebase(state: enum.Enum, data: st.DataObject) -> tuple[Machine[Any, Any, Any], int]:
    tb = Timebase(
        t_syn_s=data.draw(st.sampled_from([1, 30, 60])),
        drift_ms=data.draw(st.sampled_from([2, 10, 50, 100, 500])),
        drift_ppm=data.draw(st.floats(-25.0, 25.0)),
    )
    tb.fault = data.draw(st.booleans())
    tb.indicator = data.draw(st.integers(0, 255))
    tb.pulses = data.draw(st.integers(0, 3))
    if state in (TimeState.RECEIVED, TimeState.SET_RECEIVED):  # a time waits for a pulse
        minute = data.draw(st.integers(0, 59))
        indicator = data.draw(st.integers(0, 255))
        tb.pending = TimeReference(CivilTime(1994, 7, 15, 18, minute, 33), indicator)
    machine: Machine[Any, Any, Any] = tb.machine
    machine.state = state
    return machine, data.draw(st.integers(0, 10**9))


def _detector(state: enum.Enum, data: st.DataObject) -> tuple[Machine[Any, Any, Any], int]:
    th = Thresholds.from_config(
        data.draw(st.integers(1, 60)),
        data.draw(st.integers(1, 500)),
        data.draw(st.integers(1, 60)),
        data.draw(st.integers(1, 500)),
    )
    detector = Detector(th)
    machine: Machine[Any, Any, Any] = detector.machine
    machine.state = state
    return machine, data.draw(st.integers(0, 10**9))


def _sync_input(state: enum.Enum, data: st.DataObject) -> tuple[Machine[Any, Any, Any], int]:
    plc, mod = make()  # the input of a real, operational module
    sync = mod.sync_input
    if state is not SyncLevel.REST:
        sync.leading_edge = plc.clock.now - data.draw(st.integers(0, 500))
        sync.active = True
    machine: Machine[Any, Any, Any] = sync.machine
    machine.state = state
    plc.advance(data.draw(st.integers(0, 3)) * MS / S)
    return machine, plc.clock.now


@dataclass(frozen=True)
class Case:
    table: Table[Any, Any]
    owner: Owner


CASES = [Case(TIMEBASE, _timebase), Case(OSCILLATION, _detector), Case(SYNC_INPUT, _sync_input)]
PAIRS = [
    pytest.param(case, state, event, id=f"{case.table.name}-{state.name}-{event.name}")
    for case in CASES
    for state, event in case.table.pairs()
]


@settings(max_examples=12, deadline=None)
@given(data=st.data())
@pytest.mark.parametrize(("case", "state", "event"), PAIRS)
def test_every_pair_ends_in_its_target_or_a_protocol_error(
    case: Case, state: enum.Enum, event: enum.Enum, data: st.DataObject
) -> None:
    machine, t = case.owner(state, data)
    if case.table.allows(state, event):
        _, target = case.table.lookup(state, event)
        assert machine.fire(event, t) is target
        assert machine.state is target
    else:
        with pytest.raises(ProtocolError) as caught:
            machine.fire(event, t)
        message = str(caught.value)
        assert case.table.name in message and "can't handle" in message
        assert machine.state is state


def test_every_dem_table_is_walked() -> None:
    dem_tables = {t.name for t in tables() if t.name.startswith("DEM ")}
    assert dem_tables == {case.table.name for case in CASES}
