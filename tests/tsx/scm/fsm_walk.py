"""Walk a ``fieldtwin.fsm.Table`` on a real owner (DESIGN rule 12, issue 9 item 4).

A *rig* builds a fresh owner and says how to reach its machine and fire an input
on it.  ``check_pair`` forces the machine into a state, fires one input and
checks the table's word: a listed pair ends in its target, any other pair raises
ProtocolError and leaves the state as it was.  ``pair_ids`` names the pairs for
``pytest.mark.parametrize`` so that every pair of every table is walked.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import pytest

from fieldtwin.errors import ProtocolError
from fieldtwin.fsm import Machine, Table

S = TypeVar("S", bound=enum.Enum)
I = TypeVar("I", bound=enum.Enum)  # noqa: E741 - the table's input type


@dataclass(frozen=True, slots=True)
class Rig(Generic[S, I]):
    """How to test one table: a fresh owner's machine and its ``fire``."""

    table: Table[S, I]
    make: Callable[[], tuple[Machine[S, I, Any], Callable[[I], object]]]


def pairs(table: Table[S, I]) -> list[tuple[S, I]]:
    return list(table.pairs())


def pair_ids(table: Table[S, I]) -> list[str]:
    return [f"{state.name}-{event.name}" for state, event in table.pairs()]


def check_pair(rig: Rig[S, I], state: S, event: I) -> None:
    """One input in one state on a fresh owner: the target, or ProtocolError and no move."""
    machine, fire = rig.make()
    machine.state = state
    if rig.table.allows(state, event):
        fire(event)
        assert machine.state is rig.table.lookup(state, event)[1]
        return
    with pytest.raises(ProtocolError, match=rf"{rig.table.name}: can't handle"):
        fire(event)
    assert machine.state is state


def check_sequence(rig: Rig[S, I], steps: list[tuple[S, I]]) -> None:
    """Several (forced state, input) steps on one owner, each ending as ``check_pair`` says."""
    machine, fire = rig.make()
    for state, event in steps:
        machine.state = state
        if rig.table.allows(state, event):
            fire(event)
            assert machine.state is rig.table.lookup(state, event)[1]
        else:
            with pytest.raises(ProtocolError):
                fire(event)
            assert machine.state is state
