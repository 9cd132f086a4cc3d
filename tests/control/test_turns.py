"""The hop of the control API, by turns: the answers of one turn of the runner go back to
the web server's loop together, the loop wakes the runner once for what it submitted in
one round, a request withdrawn before its turn never runs, and the default wait is
bounded by one shared timer."""

from __future__ import annotations

import asyncio
import os
import select
import socket
from typing import Any

import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.control.sim import CommandTimeout, Sim
from fieldtwin.runtime.inbox import Answer, Inbox, InboxClosed, Ticket
from fieldtwin.runtime.runner import Runner


class Kept:
    """Replies that keep each turn's answers as they came."""

    def __init__(self) -> None:
        self.turns: list[list[Answer]] = []

    def answer(self, answers: list[Answer]) -> None:
        self.turns.append(answers)


def test_the_answers_of_a_turn_leave_together_in_order() -> None:
    inbox = Inbox()
    kept = Kept()
    for i in range(3):
        inbox.submit_ticket(lambda i=i: i * 10, Ticket(kept, f"t{i}"))
    inbox.submit_ticket(lambda: 1 // 0, Ticket(kept, "bad"))
    assert inbox.run_pending() == 4
    assert len(kept.turns) == 1  # one hand-over for the whole turn
    (turn,) = kept.turns
    assert [(key, result) for key, result, _ in turn] == [
        ("t0", 0),
        ("t1", 10),
        ("t2", 20),
        ("bad", None),
    ]
    assert isinstance(turn[3][2], ZeroDivisionError)
    assert inbox.run_pending() == 0 and len(kept.turns) == 1  # nothing: no hand-over
    inbox.close()


def test_a_ticket_withdrawn_before_its_turn_never_runs_and_a_taken_one_cannot_be() -> None:
    inbox = Inbox()
    kept = Kept()
    ran: list[str] = []
    early, late = Ticket(kept, "early"), Ticket(kept, "late")
    inbox.submit_ticket(lambda: ran.append("early"), early)
    assert inbox.withdraw(early)
    taken: list[bool] = []
    inbox.submit_ticket(lambda: taken.append(inbox.withdraw(late)) or "ran", late)
    inbox.run_pending()
    assert ran == [] and taken == [False]  # its turn had come: it runs, its effect stands
    assert [key for key, _, _ in kept.turns[0]] == ["late"]
    inbox.close()


def test_closing_answers_the_waiting_tickets() -> None:
    inbox = Inbox()
    kept = Kept()
    inbox.submit_ticket(lambda: None, Ticket(kept, "waiting"))
    inbox.close()
    ((key, _, error),) = kept.turns[0]
    assert key == "waiting" and isinstance(error, InboxClosed)


def test_the_loop_wakes_the_runner_once_for_a_round_of_commands() -> None:
    inbox = Inbox()
    sim = Sim(inbox)
    peer = socket.socket(fileno=os.dup(inbox.fileno()))  # the wakeup descriptor, to peek at
    woken: list[int] = []

    async def round_of_three() -> list[Any]:
        waiting = [asyncio.ensure_future(sim.call(lambda i=i: i)) for i in range(3)]
        await asyncio.sleep(0)  # the three submit in this round
        assert not select.select([peer], [], [], 0)[0]  # not woken yet: the round goes on
        await asyncio.sleep(0)  # the round's end: one wakeup
        woken.append(len(peer.recv(16, socket.MSG_PEEK)))
        assert inbox.run_pending() == 3  # one turn takes them all
        return await asyncio.gather(*waiting)

    try:
        assert asyncio.run(round_of_three()) == [0, 1, 2]
        assert woken == [1]
    finally:
        peer.close()
        inbox.close()


@pytest.mark.parametrize("shared", [True, False], ids=["default-wait", "own-wait"])
def test_a_request_not_taken_in_time_answers_504_and_its_command_never_runs(
    shared: bool,
) -> None:
    inbox = Inbox()
    sim = Sim(inbox, default_wait_s=0.02 if shared else 10.0)
    ran: list[str] = []

    async def late() -> None:
        answered = await sim.call(lambda: "answered", wait_s=0.02)  # taken in time
        assert answered == "answered"
        await sim.call(lambda: ran.append("late"), wait_s=0.02)

    async def both() -> None:
        async def take_first() -> None:
            while not inbox.run_pending():
                await asyncio.sleep(0.001)

        await asyncio.gather(late(), take_first())

    with pytest.raises(CommandTimeout, match=r"within 0\.02 s"):
        asyncio.run(both())
    inbox.run_pending()
    assert ran == [] and inbox.executed == 1  # withdrawn before its turn
    inbox.close()


def test_a_command_that_runs_the_clock_lets_the_answers_before_it_leave_first() -> None:
    """The answers of a turn wait for its end, except behind a command that runs the clock
    (a console exchange): those before it leave when it starts."""
    clock = SimClock()
    runner = Runner(clock, None)
    inbox = Inbox()
    runner.take_commands(inbox)
    kept = Kept()
    seen_during: list[int] = []

    def long() -> str:
        runner.step(5 * MS)  # a nested run of the clock, inside the command
        seen_during.append(len(kept.turns))
        return "long"

    inbox.submit_ticket(lambda: "quick", Ticket(kept, "quick"))
    inbox.submit_ticket(long, Ticket(kept, "long"))
    runner.step(1 * MS)  # the runner's cycle takes the turn
    assert seen_during == [1]  # "quick" had left before "long" ended
    assert [[key for key, _, _ in turn] for turn in kept.turns] == [["quick"], ["long"]]
    inbox.close()
