"""The RTU framer's transition table (fieldtwin.fsm): every (state, input) pair walked."""

from __future__ import annotations

import enum
from collections.abc import Sequence

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.fsm import Machine
from fieldtwin.modbus.pdu import request_length
from fieldtwin.modbus.rtu import FRAMER, Input, RtuFramer, State
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.transports.base import line_settings
from tests.modbus.fsm_walk import fire_and_check, walk_every_pair

TIMING = RtuTiming.from_format(line_settings(9600, 8, "E", 1))


def _args(event: enum.Enum, data: bytes = b"\x01\x03", at: int = 10_000) -> Sequence[object]:
    if event in (Input.CHAR, Input.LATE_CHAR):
        return (data,)
    if event is Input.SILENCE:
        return (at,)
    return ()


def _machine_in(state: enum.Enum) -> Machine[enum.Enum, enum.Enum, object]:
    framer = RtuFramer(TIMING, request_length)
    machine = framer._machine
    machine.state = state  # type: ignore[assignment]
    return machine  # type: ignore[return-value]


def test_every_pair_is_legal_or_a_protocol_error() -> None:
    assert walk_every_pair(FRAMER, _machine_in, _args) == len(State) * len(Input)  # type: ignore[arg-type]


@given(
    st.sampled_from(list(State)),
    st.lists(
        st.tuples(st.sampled_from(list(Input)), st.binary(max_size=300), st.integers(0, 10**9)),
        max_size=20,
    ),
)
def test_any_sequence_of_inputs_follows_the_table(
    start: State, steps: list[tuple[Input, bytes, int]]
) -> None:
    machine = _machine_in(start)
    for event, data, at in steps:
        fire_and_check(machine, event, _args(event, data, at))
