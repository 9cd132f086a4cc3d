"""The inbox's wakeup descriptor is read only when a wakeup was sent, and never left
readable with nothing to read it (docs/decisions.md, "The runner's cycle"): a runner
that reads it only when the count of wakeups sent moves must still drain every byte,
or its wait would return at once for ever."""

from __future__ import annotations

import random
import select
import threading

import pytest

from fieldtwin.runtime.inbox import WAKEUPS_READ, Answer, Inbox, Ticket

ROUNDS = 400


def _readable(inbox: Inbox) -> bool:
    ready, _, _ = select.select([inbox.fileno()], [], [], 0)
    return bool(ready)


def test_an_idle_turn_reads_nothing() -> None:
    inbox = Inbox()
    try:
        reads = 0
        real = inbox._drain_wakeups

        def counted() -> None:
            nonlocal reads
            reads += 1
            real()

        inbox._drain_wakeups = counted  # type: ignore[method-assign]
        for _ in range(5):
            assert inbox.run_pending() == 0
        assert reads == 0  # nothing was sent: no system call
        inbox.submit(lambda: 1)
        assert inbox.run_pending() == 1
        assert reads == 1 and not _readable(inbox)
        assert inbox.run_pending() == 0
        assert reads == 1
    finally:
        inbox.close()


def test_every_wakeup_the_descriptor_holds_is_read() -> None:
    """As many wakeups as the descriptor takes (a Unix socket pair holds a few hundred
    one-byte sends; a TCP pair, elsewhere, can hold more than one read takes) are read by
    one turn."""
    inbox = Inbox()
    try:
        for _ in range(WAKEUPS_READ * 2 + 7):
            inbox.wake()
        assert _readable(inbox)
        assert inbox.run_pending() == 0
        assert not _readable(inbox)
    finally:
        inbox.close()


@pytest.mark.parametrize("seed", range(4))
def test_wakeups_from_another_thread_never_stay_unread(seed: int) -> None:
    """A thread submits (waking at once, or deferring the wakeup and sending it by
    ``wake``) while this one takes turns; once both are done, one more turn leaves the
    descriptor unreadable and every command ran."""
    rng = random.Random(seed)
    inbox = Inbox(max_pending=ROUNDS)
    plan = [rng.random() < 0.5 for _ in range(ROUNDS)]
    done = threading.Event()

    def submitter() -> None:
        for defer in plan:
            if defer:
                inbox.submit_ticket(lambda: None, _ticket(), wake=False)
                inbox.wake()
            else:
                inbox.submit(lambda: None)
        done.set()

    thread = threading.Thread(target=submitter)
    try:
        thread.start()
        ran = 0
        for _ in range(100 * ROUNDS):  # bounded
            ran += inbox.run_pending()
            if done.is_set() and ran == ROUNDS:
                break
        thread.join(10)
        ran += inbox.run_pending()
        assert ran == ROUNDS
        inbox.run_pending()
        assert not _readable(inbox)
    finally:
        thread.join(10)
        inbox.close()


class _Ignore:
    def answer(self, answers: list[Answer]) -> None:
        pass


def _ticket() -> Ticket:
    return Ticket(_Ignore(), 0)
