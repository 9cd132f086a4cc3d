"""The state-machine kernel (DESIGN rule 4): one table per machine.

A machine is a mapping ``{(State, Input): (action, State)}``.  The state is set
to the target *before* the action runs, so an action may fire a follow-up
input and sees the state it was taken to (as h2's ``stream.py`` does).  A pair
that is not in the table is a ``ProtocolError`` naming the machine, the state
and the input, never a silent no-op::

    class Door(enum.Enum): SHUT = "shut"; OPEN = "open"
    class Push(enum.Enum): OPEN = "open"; SHUT = "shut"

    DOOR = Table("door", Door, Push, {
        (Door.SHUT, Push.OPEN): (Lock.ring, Door.OPEN),   # action(owner, *args)
        (Door.OPEN, Push.SHUT): (None, Door.SHUT),        # no action
    })
    machine = Machine(DOOR, Door.SHUT, owner)
    machine.fire(Push.OPEN)

Actions are plain functions of the owner (``Lock.ring(self, *args)``), so the
table is built once per class, not once per instance.  Every table built here
is listed by ``tables()``; the generated tests walk every (state, input) pair
of each.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from fieldtwin.errors import ProtocolError

S = TypeVar("S", bound=enum.Enum)
I = TypeVar("I", bound=enum.Enum)  # noqa: E741 - the table's input type
O = TypeVar("O")  # noqa: E741 - the owner the actions act on

Action = Callable[..., object]

_TABLES: list[Table[enum.Enum, enum.Enum]] = []


@dataclass(frozen=True, slots=True)
class Table(Generic[S, I]):
    """One machine's transitions: ``{(state, input): (action or None, target)}``."""

    name: str
    states: type[S]
    inputs: type[I]
    transitions: Mapping[tuple[S, I], tuple[Action | None, S]] = field(repr=False)

    def __post_init__(self) -> None:
        for (state, event), (action, target) in self.transitions.items():
            if not isinstance(state, self.states) or not isinstance(target, self.states):
                raise TypeError(f"{self.name}: {state!r} -> {target!r} is not a {self.states}")
            if not isinstance(event, self.inputs):
                raise TypeError(f"{self.name}: {event!r} is not a {self.inputs}")
            if action is not None and not callable(action):
                raise TypeError(f"{self.name}: action for {(state, event)} is not callable")
        _TABLES.append(self)  # type: ignore[arg-type]

    def lookup(self, state: S, event: I) -> tuple[Action | None, S]:
        """The (action, target) of a pair; ProtocolError naming both when it is missing."""
        try:
            return self.transitions[(state, event)]
        except KeyError:
            raise ProtocolError(
                f"{self.name}: can't handle {_name(event)} in state {_name(state)}"
            ) from None

    def allows(self, state: S, event: I) -> bool:
        return (state, event) in self.transitions

    def pairs(self) -> Iterator[tuple[S, I]]:
        """Every (state, input) pair, legal or not, in declaration order."""
        for state in self.states:
            for event in self.inputs:
                yield state, event


class Machine(Generic[S, I, O]):
    """A running machine: a table, the current state and the owner its actions act on."""

    __slots__ = ("owner", "state", "table")

    def __init__(self, table: Table[S, I], initial: S, owner: O) -> None:
        self.table = table
        self.state = initial
        self.owner = owner

    def fire(self, event: I, *args: object) -> S:
        """Take ``event``: move to the target state, then run the action with ``args``."""
        action, target = self.table.lookup(self.state, event)
        self.state = target
        if action is not None:
            action(self.owner, *args)
        return target

    def can(self, event: I) -> bool:
        return self.table.allows(self.state, event)

    def __repr__(self) -> str:
        return f"<Machine {self.table.name} in {_name(self.state)}>"


def tables() -> list[Table[enum.Enum, enum.Enum]]:
    """Every table built so far (import the packages first)."""
    return list(_TABLES)


def _name(member: enum.Enum) -> str:
    return member.name if not isinstance(member.value, str) else repr(member.value)


__all__ = ["Action", "Machine", "Table", "tables"]
