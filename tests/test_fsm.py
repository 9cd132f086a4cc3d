"""The state-machine kernel: lookups, missing pairs, action order."""

from __future__ import annotations

import enum

import pytest

from fieldtwin.errors import ProtocolError
from fieldtwin.fsm import Machine, Table, tables


class Door(enum.Enum):
    SHUT = "shut"
    OPEN = "open"


class Push(enum.Enum):
    OPEN = "open"
    SHUT = "shut"


class Owner:
    def __init__(self) -> None:
        self.seen: list[tuple[Door, object]] = []
        self.machine: Machine[Door, Push, Owner] = Machine(DOOR, Door.SHUT, self)

    def ring(self, arg: object = None) -> None:
        self.seen.append((self.machine.state, arg))


DOOR = Table(
    "door",
    Door,
    Push,
    {(Door.SHUT, Push.OPEN): (Owner.ring, Door.OPEN), (Door.OPEN, Push.SHUT): (None, Door.SHUT)},
)


def test_action_runs_after_the_state_is_set_with_the_args() -> None:
    owner = Owner()
    assert owner.machine.fire(Push.OPEN, 7) is Door.OPEN
    assert owner.seen == [(Door.OPEN, 7)]
    owner.machine.fire(Push.SHUT)
    assert owner.machine.state is Door.SHUT


def test_a_missing_pair_names_the_machine_state_and_input() -> None:
    owner = Owner()
    with pytest.raises(ProtocolError, match=r"door: can't handle 'shut' in state 'shut'"):
        owner.machine.fire(Push.SHUT)
    assert owner.machine.state is Door.SHUT


def test_pairs_cover_the_product_and_tables_are_listed() -> None:
    assert len(list(DOOR.pairs())) == 4
    assert DOOR.allows(Door.SHUT, Push.OPEN) and not DOOR.allows(Door.OPEN, Push.OPEN)
    assert DOOR in tables()


def test_a_table_with_a_foreign_state_is_refused() -> None:
    with pytest.raises(TypeError):
        Table("bad", Door, Push, {(Push.OPEN, Push.OPEN): (None, Door.OPEN)})  # type: ignore[dict-item]
