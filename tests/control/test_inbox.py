"""Commands from other threads enter the simulation between instants, in order, bounded."""

from __future__ import annotations

import asyncio
import os
import select
import socket
import threading
from collections.abc import Iterator
from concurrent.futures import Future

import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.control.sim import CommandTimeout, Sim
from fieldtwin.runtime.inbox import Inbox, InboxClosed, InboxFull
from fieldtwin.runtime.runner import Runner

WAIT_S = 10.0


def test_commands_run_in_order_on_the_thread_that_takes_them() -> None:
    inbox = Inbox()
    seen: list[int] = []
    futures = [inbox.submit(lambda i=i: seen.append(i) or i) for i in range(5)]
    assert seen == [] and len(inbox) == 5
    assert inbox.run_pending() == 5
    assert seen == [0, 1, 2, 3, 4]
    assert [f.result(0) for f in futures] == [0, 1, 2, 3, 4]
    inbox.close()


def test_an_error_goes_to_its_requester_and_the_next_command_still_runs() -> None:
    inbox = Inbox()
    bad = inbox.submit(lambda: 1 // 0)
    good = inbox.submit(lambda: "ok")
    inbox.run_pending()
    with pytest.raises(ZeroDivisionError):
        bad.result(0)
    assert good.result(0) == "ok"
    inbox.close()


def test_the_inbox_is_bounded_and_a_cancelled_command_never_runs() -> None:
    inbox = Inbox(max_pending=2)
    ran: list[str] = []
    first = inbox.submit(lambda: ran.append("first"))
    inbox.submit(lambda: ran.append("second"))
    with pytest.raises(InboxFull):
        inbox.submit(lambda: ran.append("third"))
    assert first.cancel()
    inbox.run_pending()
    assert ran == ["second"]
    inbox.close()


def test_closing_fails_the_waiting_commands_and_refuses_new_ones() -> None:
    inbox = Inbox()
    waiting = inbox.submit(lambda: None)
    inbox.close()
    with pytest.raises(InboxClosed):
        waiting.result(0)
    with pytest.raises(InboxClosed):
        inbox.submit(lambda: None)


def test_the_wakeup_descriptor_is_readable_while_commands_wait() -> None:
    inbox = Inbox()
    assert not inbox.wait(0)
    inbox.submit(lambda: None)
    assert inbox.wait(0)
    inbox.run_pending()
    assert not inbox.wait(0)
    inbox.close()


def test_a_command_runs_between_instants_of_a_run() -> None:
    clock = SimClock()
    runner = Runner(clock, None)
    inbox = Inbox()
    runner.take_commands(inbox)
    at: list[int] = []
    clock.schedule(10 * MS, lambda now: inbox.submit(lambda: at.append(clock.now)))
    runner.run_until(lambda: bool(at), 1000 * MS)
    assert at == [10 * MS]  # taken at the start of the next cycle, at the same instant
    runner.take_commands(None)
    inbox.close()


@pytest.fixture()
def running() -> Iterator[tuple[Runner, Inbox]]:
    """A runner in run_forever on its own thread (x1, nothing attached: it waits on
    the wall, woken by the inbox), stopped and joined at the end (bounded)."""
    clock = SimClock()
    runner = Runner(clock, 1.0)
    inbox = Inbox()
    runner.take_commands(inbox)
    thread = threading.Thread(target=runner.run_forever, daemon=True)
    thread.start()
    yield runner, inbox
    runner.stop()
    thread.join(WAIT_S)
    assert not thread.is_alive()
    inbox.close()


def call(inbox: Inbox, fn: object) -> object:
    future: Future[object] = inbox.submit(fn)  # type: ignore[arg-type]
    return future.result(WAIT_S)


def test_paused_time_stands_still_and_steps_by_exactly_what_is_asked(
    running: tuple[Runner, Inbox],
) -> None:
    runner, inbox = running
    call(inbox, runner.pause)
    t0 = call(inbox, lambda: runner.clock.now)
    for _ in range(5):  # each round trip is a pass of the paused loop
        assert call(inbox, lambda: runner.clock.now) == t0
    assert call(inbox, lambda: runner.paused) is True
    call(inbox, lambda: runner.step(50 * MS))
    assert call(inbox, lambda: runner.clock.now) == t0 + 50 * MS  # type: ignore[operator]
    call(inbox, lambda: runner.run_to(t0 + 80 * MS))  # type: ignore[operator]
    assert call(inbox, lambda: runner.clock.now) == t0 + 80 * MS  # type: ignore[operator]
    call(inbox, lambda: runner.set_speed(50.0))
    call(inbox, runner.resume)
    assert call(inbox, lambda: (runner.paused, runner.speed)) == (False, 50.0)


def test_a_stop_inside_a_command_s_own_run_ends_the_run_around_it() -> None:
    clock = SimClock()
    runner = Runner(clock, None)
    inbox = Inbox()
    runner.take_commands(inbox)
    clock.schedule(5 * MS, lambda now: runner.stop())

    def nested() -> None:
        runner.step(20 * MS)  # the stop at 5 ms ends it, and the run_forever around it

    inbox.submit(nested)
    runner.run_forever()
    assert clock.now == 5 * MS
    runner.take_commands(None)
    inbox.close()


def test_commands_waiting_share_one_wakeup_and_run_in_one_turn() -> None:
    inbox = Inbox()
    peer = socket.socket(fileno=os.dup(inbox.fileno()))  # the wakeup descriptor, to peek at
    try:
        ran: list[int] = []
        for i in range(3):
            inbox.submit(lambda i=i: ran.append(i))
        assert select.select([peer], [], [], 0)[0]
        assert len(peer.recv(16, socket.MSG_PEEK)) == 1  # the first command's wakeup only
        assert inbox.run_pending() == 3 and ran == [0, 1, 2]
        assert not select.select([peer], [], [], 0)[0]
        inbox.submit(lambda: ran.append(3))  # after the turn: a wakeup of its own
        assert select.select([peer], [], [], 0)[0]
        assert inbox.run_pending() == 1 and ran == [0, 1, 2, 3]
    finally:
        peer.close()
        inbox.close()


def test_a_command_not_taken_in_time_times_out_and_never_runs() -> None:
    inbox = Inbox()
    ran: list[str] = []
    sim = Sim(inbox)

    async def late() -> None:
        await sim.call(lambda: ran.append("late"), wait_s=0.01)

    with pytest.raises(CommandTimeout, match=r"within 0\.01 s"):
        asyncio.run(late())
    inbox.run_pending()
    assert ran == [] and inbox.executed == 0  # cancelled before its turn
    inbox.close()


def test_a_request_cancelled_while_waiting_is_cancelled_not_timed_out() -> None:
    inbox = Inbox()
    sim = Sim(inbox)

    async def cancelled() -> None:
        waiting = asyncio.ensure_future(sim.call(lambda: None, wait_s=WAIT_S))
        await asyncio.sleep(0)  # the request waits for its command
        waiting.cancel()
        with pytest.raises(asyncio.CancelledError):
            await waiting

    asyncio.run(cancelled())
    inbox.run_pending()
    assert inbox.executed == 0  # cancelled with its request
    inbox.close()
