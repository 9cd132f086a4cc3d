"""Issue 26 item 3: a stop is a latch only the run it ends consumes; a stop asked before
or during start-up ends the run at once.  A scripted wall clock, except where the real
signal handler of ``fieldtwin run`` is exercised."""

from __future__ import annotations

import signal

import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wall import SystemWall
from fieldtwin.transports.tcp import listen
from tests.runtime.fake_wall import START, FakeLine, FakeWall

TICK_BOUND = 50  # ticks a run_forever that should have ended at once may take before failing


def _bounded_ticks(runner: Runner, ticks: list[int]) -> None:
    """run_forever whose ticks fail the test past TICK_BOUND (a stop that was lost)."""

    def tick(now: int) -> None:
        ticks.append(now)
        if len(ticks) >= TICK_BOUND:
            runner.stop()

    runner.run_forever(tick, tick_us=10 * MS)


def test_a_stop_that_comes_as_a_run_ends_by_its_predicate_is_kept_for_the_next_run() -> None:
    clock, wall = SimClock(), FakeWall()
    runner = Runner(clock, 1.0, wall=wall)
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    clock.schedule(5 * MS, lambda now: None)

    asked: list[int] = []

    def reached() -> bool:  # the stop arrives as the predicate ends the run (a race)
        if clock.now >= 5 * MS and not asked:
            asked.append(clock.now)
            runner.stop()
        return bool(asked)

    assert runner.run_until(reached, 100 * MS)
    assert asked == [5 * MS]
    assert runner.stopping  # the run ended by its predicate: the stop is not its
    waits = len(wall.waits)
    ticks: list[int] = []
    _bounded_ticks(runner, ticks)
    assert ticks == [] and len(wall.waits) == waits and clock.now == 5 * MS  # at once
    assert not runner.stopping  # taken down by the run it ended


def test_a_stop_asked_between_two_runs_ends_the_next_and_only_that_one() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    runner.advance(20 * MS)
    runner.stop()  # after the run: not consumed by it
    assert runner.stopping
    runner.advance(20 * MS)
    assert clock.now == 20 * MS  # the next run ended at once
    assert not runner.stopping
    runner.advance(20 * MS)
    assert clock.now == 40 * MS  # and the one after runs


def test_a_stop_asked_before_a_nested_run_passes_on_to_the_run_around_it() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    inbox = Inbox()
    runner.take_commands(inbox)
    seen: list[bool] = []

    def command() -> None:  # a command asks the stop, then runs the clock itself
        runner.stop()
        runner.advance(10 * MS)
        seen.append(runner.stopping)

    inbox.submit(command)
    try:
        ticks: list[int] = []
        _bounded_ticks(runner, ticks)
    finally:
        runner.take_commands(None)
        inbox.close()
    assert seen == [True]  # the nested run ended at once and passed the stop on
    assert clock.now == 0 and ticks == []
    assert not runner.stopping


def test_a_stop_queued_as_the_first_command_ends_the_run_before_any_time_passes() -> None:
    clock, wall = SimClock(), FakeWall()
    runner = Runner(clock, 1.0, wall=wall)
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    clock.schedule(MS, lambda now: None)
    inbox = Inbox()
    runner.take_commands(inbox)
    inbox.submit(runner.stop)  # during start-up: the run has not begun
    try:
        runner.run_forever()
    finally:
        runner.take_commands(None)
        inbox.close()
    assert clock.now == 0 and wall.now == START and wall.waits == []
    assert not runner.stopping


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="POSIX signals")
@pytest.mark.usefixtures("signal_handlers")
def test_sigterm_during_start_up_ends_the_run_at_once() -> None:
    """``fieldtwin run``'s own handler (cli.stop_on_signals): a SIGTERM that comes while
    the ports are being bound ends ``run_forever`` at once, before its deadline."""
    from fieldtwin.cli import stop_on_signals

    clock, wall = SimClock(), SystemWall()
    runner = Runner(clock, 1.0, wall=wall)
    stop_on_signals(runner)
    listener = listen("127.0.0.1", 0)
    try:
        runner.attach_listener(listener, lambda transport, now: transport.close())
        signal.raise_signal(signal.SIGTERM)  # start-up is not over: more ports to bind
        assert runner.stopping
        clock.schedule(10 * MS, lambda now: None)
        ticks: list[int] = []
        _bounded_ticks(runner, ticks)  # KeyboardInterrupt at the deadline: not here
        assert ticks == [] and clock.now == 0
        assert not runner.stopping
    finally:
        runner.detach(listener)
        listener.close()
        wall.close()
