"""Issue 13: at ``--speed max`` a wall with ``fast_poll_s`` is polled between two
instants only once that much wall time has passed since the last poll; bytes that
arrived meanwhile get the instant of the poll that finds them.  Walls without it
(the tests' FakeWall) are polled between every two instants (test_runner_pacing)."""

from __future__ import annotations

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wall import FAST_POLL_S, SystemWall
from tests.runtime.fake_wall import START, FakeLine, FakeWall

Log = list[tuple[str, int]]


class SlowPollWall(FakeWall):
    fast_poll_s = 0.001


def _setup() -> tuple[SimClock, SlowPollWall, Runner, FakeLine, Log]:
    clock = SimClock()
    wall = SlowPollWall()
    runner = Runner(clock, None, wall=wall)
    line = FakeLine(fd=10)
    log: Log = []
    runner.attach(line, lambda data, now: log.append((data.decode(), now)))
    return clock, wall, runner, line, log


def _busy(clock: SimClock, wall: SlowPollWall, log: Log, count: int, spend: float) -> None:
    """``count`` events 1 ms apart, each taking ``spend`` s of wall time."""

    def event(now: int) -> None:
        log.append(("event", now))
        wall.spend(spend)

    for i in range(1, count + 1):
        clock.schedule(i * MS, event)


def test_the_system_wall_asks_for_fewer_polls() -> None:
    wall = SystemWall()
    try:
        assert wall.fast_poll_s == FAST_POLL_S > 0
    finally:
        wall.close()


def test_no_wall_time_passing_means_one_poll() -> None:
    clock, wall, runner, _, log = _setup()
    _busy(clock, wall, log, 5, 0.0)
    runner.advance(S)
    assert wall.waits[0] == 0 and wall.waits.count(0) == 1  # the first instant only
    assert [now for _, now in log] == [1 * MS, 2 * MS, 3 * MS, 4 * MS, 5 * MS]
    assert clock.now == S


def test_a_poll_once_fast_poll_s_has_passed() -> None:
    clock, wall, runner, _, log = _setup()
    _busy(clock, wall, log, 10, 0.0004)  # 0.4 ms of wall per event
    runner.advance(10 * MS)
    # polls at wall 0 (before 1 ms), then after the events ending at 1.2, 2.4, 3.6 ms
    assert wall.waits == [0, 0, 0, 0]
    assert clock.now == 10 * MS


def test_bytes_get_the_instant_of_the_poll_that_finds_them() -> None:
    clock, wall, runner, line, log = _setup()
    _busy(clock, wall, log, 10, 0.0004)
    wall.data_at(0.0001, line, b"request")  # lands while the first event runs
    runner.advance(10 * MS)
    # polled before 1 ms (wall 0: not yet there), then before 4 ms (wall 1.2 ms)
    assert ("request", 3 * MS) in log
    assert log.index(("request", 3 * MS)) == 3  # after events 1, 2, 3, before 4
    assert wall.now - START > 0.001


def test_a_run_with_nothing_due_still_waits_for_the_peer_at_x1() -> None:
    clock, wall, runner, line, log = _setup()
    wall.data_at(0.3, line, b"late")
    runner.advance(2 * S)
    assert log == [("late", 300 * MS)]
    assert clock.now == 2 * S


def _ticked(wall: FakeWall) -> tuple[Log, list[int], int]:
    """Events every 3 ms, ticks every 2 ms, a stop at the 7th tick; what was seen."""
    clock = SimClock()
    runner = Runner(clock, None, wall=wall)
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    log: Log = []
    for i in range(1, 40):
        clock.schedule(i * 3 * MS, lambda now: log.append(("event", now)))
    ticks: list[int] = []

    def on_tick(now: int) -> None:
        ticks.append(now)
        if len(ticks) == 7:
            runner.stop()

    runner.run_forever(on_tick, tick_us=2 * MS)
    return log, ticks, clock.now


def test_ticks_and_stops_fall_on_the_same_instants_as_with_a_poll_per_instant() -> None:
    assert _ticked(SlowPollWall()) == _ticked(FakeWall())


def _until_five(wall: FakeWall) -> tuple[Log, int]:
    clock = SimClock()
    runner = Runner(clock, None, wall=wall)
    runner.attach(FakeLine(fd=10), lambda data, now: None)
    log: Log = []
    for i in range(1, 20):
        clock.schedule(i * MS, lambda now: log.append(("event", now)))
    assert runner.run_until(lambda: len(log) == 5, S)
    return log, clock.now


def test_run_until_stops_at_the_same_instant_between_polls() -> None:
    seen = _until_five(SlowPollWall())
    assert seen == _until_five(FakeWall())
    assert seen[1] == 5 * MS


def test_every_run_polls_before_its_first_instant() -> None:
    clock, wall, runner, line, log = _setup()
    _busy(clock, wall, log, 10, 0.0)
    runner.advance(5 * MS)  # polled once, at 0 (no wall time passes)
    wall.data_at(0.0, line, b"between runs")  # e.g. sent by the caller between two runs
    runner.advance(5 * MS)
    assert log.index(("between runs", 5 * MS)) == 5  # before the event at 6 ms
    assert wall.waits == [0, 0, 0]  # each run's first poll, then the one after the bytes


def test_after_bytes_the_next_instant_polls_again() -> None:
    clock, wall, runner, line, log = _setup()
    _busy(clock, wall, log, 5, 0.0)
    wall.data_at(0.0, line, b"first")
    runner.advance(10 * MS)
    # the run's first poll finds bytes, so the next instant polls again (none: the
    # polls then wait for fast_poll_s of wall time, which does not pass here); after
    # the last event, nothing is due: the idle wait for a peer up to the end
    assert wall.waits == [0, 0, 0.005]
    assert log[0] == ("first", 0)
