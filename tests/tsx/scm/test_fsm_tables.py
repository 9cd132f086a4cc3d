"""Every (state, input) pair of the SCM's machines, on a real channel (issue 9 item 4).

Each test forces a channel of a real module in a PLC into a state and fires an
input: a pair of the table ends in its target, any other raises ProtocolError.
The channel holds a real request (job and exchange) so every action can run.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.fsm import Machine, tables
from fieldtwin.tsx.scm import requests as reqmod
from fieldtwin.tsx.scm.fullduplex import FD_READ, FD_WRITE, Direction, FdInput, FullDuplexChannel
from fieldtwin.tsx.scm.halfduplex import HALF_DUPLEX, HalfDuplexChannel, HdInput, HdState
from fieldtwin.tsx.textblock import Exchange, Request
from fieldtwin.words import words_to_bytes
from tests.tsx.scm.fsm_walk import Rig, check_pair, check_sequence, pair_ids, pairs
from tests.tsx.scm.helpers import CONFIG_3_3
from tests.tsx.scm.helpers import ready as ready_hd
from tests.tsx.scm.test_fullduplex import fd

# request 5: 1 s time-out, 3 characters to receive, then "AB" to send (AMB-SCM-12)
WRITE_READ = words_to_bytes([0x0010, 3]) + b"AB"


def _exchange(code: int, data: bytes, now: int) -> Exchange:
    return Exchange(Request(code, 0, data, 20), now, lambda exchange, at: None)


def _half_duplex() -> tuple[Machine[HdState, HdInput, Any], Callable[[HdInput], object]]:
    plc, mod, peer = ready_hd(words=CONFIG_3_3)
    channel = mod.channels[0]
    assert isinstance(channel, HalfDuplexChannel)
    now = plc.now
    channel.job = reqmod.parse(reqmod.TXRX_TIMEOUT, WRITE_READ)
    channel.exchange = _exchange(reqmod.TXRX_TIMEOUT, WRITE_READ, now)
    return channel.machine, lambda event: channel.fire(event, now)


def _full_duplex(
    direction: Direction,
) -> Callable[[], tuple[Machine[Any, FdInput, Any], Callable[[FdInput], object]]]:
    def make() -> tuple[Machine[Any, FdInput, Any], Callable[[FdInput], object]]:
        plc, mod, peer = fd()
        channel = mod.channels[1]
        assert isinstance(channel, FullDuplexChannel)
        now = plc.now
        data = words_to_bytes([0x0010, 3])  # request 7: read 3 (or the write below)
        if direction is Direction.WRITE:
            data = words_to_bytes([0x0010, 0]) + b"AB"
        channel.jobs[direction] = reqmod.parse(reqmod.COMBINED, data)
        channel.exchanges[direction] = _exchange(reqmod.COMBINED, data, now)
        return channel.machines[direction], lambda event: channel.fire(direction, event, now)

    return make


HD_RIG = Rig(HALF_DUPLEX, _half_duplex)
FD_RIGS = {FD_WRITE.name: Rig(FD_WRITE, _full_duplex(Direction.WRITE))}
FD_RIGS[FD_READ.name] = Rig(FD_READ, _full_duplex(Direction.READ))


@pytest.mark.parametrize(("state", "event"), pairs(HALF_DUPLEX), ids=pair_ids(HALF_DUPLEX))
def test_every_half_duplex_pair(state: HdState, event: HdInput) -> None:
    check_pair(HD_RIG, state, event)


@pytest.mark.parametrize(("state", "event"), pairs(FD_WRITE), ids=pair_ids(FD_WRITE))
def test_every_full_duplex_write_pair(state: Any, event: FdInput) -> None:
    check_pair(FD_RIGS[FD_WRITE.name], state, event)


@pytest.mark.parametrize(("state", "event"), pairs(FD_READ), ids=pair_ids(FD_READ))
def test_every_full_duplex_read_pair(state: Any, event: FdInput) -> None:
    check_pair(FD_RIGS[FD_READ.name], state, event)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.sampled_from(pairs(HALF_DUPLEX)), min_size=1, max_size=6))
def test_half_duplex_sequences_of_forced_pairs(steps: list[tuple[HdState, HdInput]]) -> None:
    check_sequence(HD_RIG, steps)


@settings(max_examples=25, deadline=None)
@given(
    st.sampled_from([FD_WRITE.name, FD_READ.name]),
    st.lists(st.sampled_from(pairs(FD_WRITE)), min_size=1, max_size=6),
)
def test_full_duplex_sequences_of_forced_pairs(name: str, steps: list[tuple[Any, FdInput]]) -> None:
    check_sequence(FD_RIGS[name], steps)


def test_every_scm_table_is_walked() -> None:
    scm = {table.name for table in tables() if table.name.startswith("SCM ")}
    assert scm == {HALF_DUPLEX.name, FD_WRITE.name, FD_READ.name}
