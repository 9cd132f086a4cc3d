"""A local helper: walk every (state, input) pair of an ``fieldtwin.fsm.Table``.

Each pair either is in the table, and firing it lands on the table's target, or it
is not, and firing it raises ProtocolError naming the machine, the state and the
input and leaves the state alone (DESIGN rule 4).
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence

import pytest

from fieldtwin.errors import ProtocolError
from fieldtwin.fsm import Machine, Table


def fire_and_check(
    machine: Machine[enum.Enum, enum.Enum, object], event: enum.Enum, args: Sequence[object]
) -> None:
    """Fire one input; assert the outcome the table promises."""
    table: Table[enum.Enum, enum.Enum] = machine.table
    before = machine.state
    if table.allows(before, event):
        _, target = table.lookup(before, event)
        machine.fire(event, *args)
        assert machine.state is target, f"{table.name}: {before} + {event} -> {machine.state}"
    else:
        with pytest.raises(ProtocolError) as info:
            machine.fire(event, *args)
        message = str(info.value)
        assert table.name in message and repr(event.value) in message
        assert repr(before.value) in message
        assert machine.state is before


def walk_every_pair(
    table: Table[enum.Enum, enum.Enum],
    machine_in: Callable[[enum.Enum], Machine[enum.Enum, enum.Enum, object]],
    args_for: Callable[[enum.Enum], Sequence[object]],
) -> int:
    """Fire every input in every state on a fresh machine; the number of pairs walked."""
    count = 0
    for state, event in table.pairs():
        fire_and_check(machine_in(state), event, args_for(event))
        count += 1
    return count
