"""Generated tests for state-machine tables (DESIGN rule 12, issue 9 item 4).

For a :class:`fieldtwin.fsm.Table`, walk every (state, input) pair on a real owner
forced into the state: the input ends in the table's target, or raises
ProtocolError and leaves the state as it was.  Usage, in any test module::

    from tests.fsm_check import Forced, check_every_pair, pairs_of

    def force(state: MyState) -> Forced[MyState, MyInput]:
        owner = make_a_real_owner()
        owner.machine.state = state          # forced, whatever it takes to get there
        return Forced(lambda event: owner.machine.fire(event, *args), lambda: owner.machine.state)

    def test_every_pair() -> None:
        check_every_pair(MY_TABLE, force)

    @given(pairs_of(MY_TABLE))
    def test_any_pair(pair) -> None:
        check_pair(MY_TABLE, *pair, force)

``check_every_pair`` runs the sweep as a hypothesis test (every pair is an
explicit example, so none is left to chance) and then lets hypothesis draw
short random walks from every state, each step checked the same way.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from fieldtwin.errors import ProtocolError
from fieldtwin.fsm import Table

S = TypeVar("S", bound=enum.Enum)
I = TypeVar("I", bound=enum.Enum)  # noqa: E741 - the table's input type


@dataclass(frozen=True, slots=True)
class Forced(Generic[S, I]):
    """A real owner forced into a state: how to fire an input, how to read the state."""

    fire: Callable[[I], object]
    state: Callable[[], S]


Force = Callable[[S], Forced[S, I]]


def pairs_of(table: Table[S, I]) -> st.SearchStrategy[tuple[S, I]]:
    return st.sampled_from(list(table.pairs()))


def step(table: Table[S, I], forced: Forced[S, I], event: I) -> None:
    """Fire ``event``: the table's target if the pair is in it, else ProtocolError."""
    state = forced.state()
    if table.allows(state, event):
        forced.fire(event)
        target = table.lookup(state, event)[1]
        assert forced.state() is target, (
            f"{table.name}: {state} + {event} ended in {forced.state()}, table says {target}"
        )
    else:
        with pytest.raises(ProtocolError, match="can't handle"):
            forced.fire(event)
        assert forced.state() is state, f"{table.name}: a refused {event} changed the state"


def check_pair(table: Table[S, I], state: S, event: I, force: Force[S, I]) -> None:
    forced = force(state)
    assert forced.state() is state, f"{table.name}: could not force {state}"
    step(table, forced, event)


def check_every_pair(table: Table[S, I], force: Force[S, I], walk_length: int = 6) -> None:
    """Every (state, input) pair once, then random walks from every state."""
    pairs = list(table.pairs())
    states = list(table.states)
    inputs = list(table.inputs)

    @settings(max_examples=len(pairs) + 2 * len(states))
    @given(
        st.sampled_from(states),
        st.lists(st.sampled_from(inputs), min_size=1, max_size=walk_length),
    )
    def walk(start: S, events: list[I]) -> None:
        forced = force(start)
        assert forced.state() is start, f"{table.name}: could not force {start}"
        for event in events:
            step(table, forced, event)

    for state, event in pairs:  # every pair, explicitly
        walk = example(state, [event])(walk)
    walk()


__all__ = ["Forced", "check_every_pair", "check_pair", "pairs_of", "step"]
