"""Issue 20: the stop latch, bounded catch-up with the speed reached, runner modes, speed
bounds.  A scripted wall clock: deterministic, no sleeping."""

from __future__ import annotations

from itertools import pairwise

import pytest

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.pace import CATCH_UP_SLICE_S, MAX_SPEED, MIN_SPEED, check_speed
from fieldtwin.runtime.runner import Runner
from tests.runtime.fake_wall import START, FakeLine, FakeWall


def _paced(speed: float) -> tuple[SimClock, FakeWall, Runner, FakeLine, list[str]]:
    clock, wall = SimClock(), FakeWall()
    reports: list[str] = []
    runner = Runner(clock, speed, wall=wall, report=reports.append)
    line = FakeLine(fd=10)
    runner.attach(line, lambda data, now: None)
    return clock, wall, runner, line, reports


# ------------------------------------------------------------------ the stop latch


def test_a_stop_before_the_run_ends_it_at_once() -> None:
    clock, wall, runner, _, _ = _paced(1.0)
    clock.schedule(10 * MS, lambda now: None)
    runner.stop()
    runner.run_forever()
    assert clock.now == 0 and wall.now == START and wall.waits == []
    assert not runner.stopping  # taken down by the run it ended
    runner.advance(20 * MS)  # the next run runs
    assert clock.now == 20 * MS


def test_a_stop_in_a_nested_run_ends_every_run_after_it_until_the_outermost() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    inbox = Inbox()
    runner.take_commands(inbox)
    clock.schedule(5 * MS, lambda now: runner.stop())
    inner: list[int] = []

    def command() -> None:  # a command running the clock in steps (a console advance)
        for _ in range(1000):
            runner.advance(10 * MS)
            inner.append(clock.now)

    inbox.submit(command)
    try:
        runner.run_forever()
    finally:
        runner.take_commands(None)
        inbox.close()
    assert clock.now == 5 * MS and set(inner) == {5 * MS}  # every later step: no time at all
    assert not runner.stopping


# ------------------------------------------------------------------ bounded catch-up


def test_catch_up_is_cut_into_slices_and_the_speed_reached_is_told() -> None:
    """x100000 asked, each millisecond of simulated time costs a millisecond of wall: the
    plant reaches about x1; between two looks at the descriptors at most one slice."""
    clock, wall, runner, line, reports = _paced(MAX_SPEED)
    seen: list[float] = []

    def busy(now: int) -> None:
        wall.spend(0.001)
        seen.append(wall.now)
        clock.schedule(now + MS, busy)

    clock.schedule(MS, busy)
    for i in range(300):  # a master polling every 10 ms of wall
        wall.data_at(0.01 * i, line, b"?")
    runner.advance(3 * S)
    looks = [START, *wall.called_at]
    assert max(b - a for a, b in pairwise(looks)) <= CATCH_UP_SLICE_S + 0.0015
    reached = runner.speed_reached
    assert reached is not None and 0.8 < reached < 1.2
    assert runner.lagging
    assert len(reports) == 1 and "cannot keep speed x100000" in reports[0]


def test_a_plant_that_keeps_the_speed_reaches_it() -> None:
    clock, wall, runner, _, reports = _paced(10.0)

    def tick(now: int) -> None:
        clock.schedule(now + 10 * MS, tick)

    clock.schedule(0, tick)
    runner.advance(20 * S)
    reached = runner.speed_reached
    assert reached is not None and reached == pytest.approx(10.0, rel=0.02)
    assert not runner.lagging and reports == []


# ------------------------------------------------------------------ speed bounds


@pytest.mark.parametrize("speed", [1e-300, 0.0, MIN_SPEED / 2, MAX_SPEED * 2, float("nan")])
def test_speeds_out_of_bounds_are_refused_with_the_range(speed: float) -> None:
    with pytest.raises(ConfigError, match=f"from {MIN_SPEED:g} to {MAX_SPEED:g}"):
        check_speed(speed)
    runner = Runner(SimClock(), 1.0, wall=FakeWall())
    with pytest.raises(ConfigError, match="allowed"):
        runner.set_speed(speed)
    assert runner.speed == 1.0


# ------------------------------------------------------------------ modes


def test_a_mode_ends_exactly_at_its_time_as_a_clock_event_after_the_others() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    log: list[tuple[str, int]] = []
    clock.schedule(50 * MS, lambda now: log.append(("event", now)))

    def ended(now: int, cut: bool) -> None:
        log.append((f"end cut={cut}", now))
        runner.stop()

    runner.start_mode("run-until", 50 * MS, ended)
    assert runner.mode is not None and runner.mode.name == "run-until"
    runner.run_forever()
    assert log == [("event", 50 * MS), ("end cut=False", 50 * MS)]
    assert runner.mode is None and clock.now == 50 * MS


def test_a_paused_runner_runs_a_mode_to_its_end_then_holds_and_pause_cuts_a_mode() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    inbox = Inbox()
    runner.take_commands(inbox)
    ends: list[tuple[str, int, bool]] = []
    held: list[int] = []

    def every_ms(now: int) -> None:  # something to do: the runner takes commands between
        clock.schedule(now + MS, every_ms)

    clock.schedule(MS, every_ms)

    def second_mode() -> None:
        held.append(clock.now)  # the first mode has ended; paused: time holds
        runner.start_mode("step", clock.now + S, lambda now, cut: ends.append(("step", now, cut)))
        inbox.submit(lambda: (runner.pause(), runner.stop()))

    def first_end(now: int, cut: bool) -> None:
        ends.append(("run-until", now, cut))
        inbox.submit(second_mode)

    inbox.submit(runner.pause)
    inbox.submit(lambda: runner.start_mode("run-until", 30 * MS, first_end))
    try:
        runner.run_forever()
    finally:
        runner.take_commands(None)
        inbox.close()
    assert ends[0] == ("run-until", 30 * MS, False)
    assert held == [30 * MS]
    assert ends[1][0] == "step" and ends[1][2] is True  # the pause cut it
    assert ends[1][1] < 30 * MS + S
    assert runner.paused and runner.mode is None


def test_a_new_mode_replaces_the_one_in_progress() -> None:
    clock = SimClock()
    runner = Runner(clock, None, wall=FakeWall())
    ends: list[tuple[str, int, bool]] = []
    runner.start_mode("run-until", 1000 * S, lambda now, cut: ends.append(("a", now, cut)))
    runner.start_mode("step", 10 * MS, lambda now, cut: ends.append(("b", now, cut)))
    assert ends == [("a", 0, True)]
    runner.advance(20 * MS)
    assert ends == [("a", 0, True), ("b", 10 * MS, False)]
    assert clock.next_deadline() is None  # the first mode's end event is gone
    with pytest.raises(ConfigError, match="never goes back"):
        runner.start_mode("run-until", 0)
