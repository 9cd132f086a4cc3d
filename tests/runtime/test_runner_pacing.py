"""The runner's pacing, with a scripted wall clock: deterministic, no sleeping."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.errors import ConfigError, TransportError
from fieldtwin.runtime.runner import MAX_WAIT_S, POLL_WAIT_S, Runner
from fieldtwin.transports.memory import memory_pair
from tests.runtime.fake_wall import START, FakeLine, FakeListener, FakeWall

Log = list[tuple[str, int]]


def _setup(speed: float | None = 1.0) -> tuple[SimClock, FakeWall, Runner, FakeLine, Log]:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, speed, wall=wall)
    line = FakeLine(fd=10)
    log: Log = []
    runner.attach(line, lambda data, now: log.append((data.decode(), now)))
    return clock, wall, runner, line, log


def _ticker(runner: Runner, ticks: list[int], count: int) -> Callable[[int], None]:
    """An on_tick that records ticks and stops the runner after ``count`` of them."""

    def on_tick(now: int) -> None:
        ticks.append(now)
        if len(ticks) == count:
            runner.stop()

    return on_tick


def _event(clock: SimClock, at: int, log: Log, name: str | None = None) -> None:
    clock.schedule(at, lambda now: log.append((name or f"event@{at}", now)))


def test_paced_sleeps_until_each_deadline_mapped_to_wall_time() -> None:
    clock, wall, runner, _, log = _setup()
    _event(clock, 50 * MS, log)
    runner.advance(100 * MS)
    assert log == [("event@50000", 50 * MS)]
    assert wall.waits == pytest.approx([0.05, 0.05])
    assert wall.now == pytest.approx(START + 0.1)
    assert clock.now == 100 * MS


@pytest.mark.parametrize("speed", [0.5, 2.0, 10.0, 1000.0])
def test_speed_factor_divides_wall_time(speed: float) -> None:
    clock, wall, runner, _, log = _setup(speed)
    _event(clock, 50 * MS, log)
    runner.advance(100 * MS)
    assert wall.now - START == pytest.approx(0.1 / speed)
    assert log == [("event@50000", 50 * MS)]


def test_bytes_arriving_mid_wait_get_their_simulated_arrival_time() -> None:
    clock, wall, runner, line, log = _setup(speed=10.0)
    _event(clock, 20 * MS, log)
    _event(clock, 40 * MS, log)
    wall.data_at(0.003, line, b"hello")  # 3 ms of wall at x10 = 30 ms simulated
    runner.advance(100 * MS)
    assert log == [("event@20000", 20 * MS), ("hello", 30 * MS), ("event@40000", 40 * MS)]


def test_events_at_the_arrival_instant_run_before_the_bytes() -> None:
    clock, wall, runner, line, log = _setup()
    _event(clock, 30 * MS, log)
    wall.data_at(0.030, line, b"x")
    runner.advance(50 * MS)
    assert log == [("event@30000", 30 * MS), ("x", 30 * MS)]


def test_a_lagging_clock_catches_up_without_sleeping_and_never_goes_back() -> None:
    clock, wall, runner, line, log = _setup()
    clock.schedule(10 * MS, lambda now: wall.spend(0.045))  # a callback that takes 45 ms of wall
    for at in (20 * MS, 30 * MS, 40 * MS, 60 * MS):
        _event(clock, at, log)
    wall.data_at(0.050, line, b"late")  # lands while that callback is still running
    runner.advance(100 * MS)
    assert log == [
        ("event@20000", 20 * MS),
        ("event@30000", 30 * MS),
        ("event@40000", 40 * MS),
        ("late", 55 * MS),  # seen when the runner looked again: wall 55 ms
        ("event@60000", 60 * MS),
    ]
    assert wall.waits[1] == 0  # the catch-up polls, it does not sleep
    assert wall.waits[2] == pytest.approx(0.005)  # then back on schedule for 60 ms
    assert wall.now == pytest.approx(START + 0.1)
    assert clock.now == 100 * MS


def test_bytes_already_waiting_are_delivered_at_the_current_time() -> None:
    clock, wall, runner, line, log = _setup()
    clock.advance(5 * MS)
    wall.data_at(-1.0, line, b"early")  # arrived before this advance began
    runner.advance(10 * MS)
    assert log == [("early", 5 * MS)]


def test_a_hang_up_calls_on_close_and_detaches() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, wall=wall)
    line = FakeLine(fd=11)
    closed: list[int] = []
    runner.attach(line, lambda data, now: None, closed.append)
    wall.data_at(0.020, line, b"")
    runner.advance(50 * MS)
    assert closed == [20 * MS]
    assert not runner.paced  # nothing real is attached any more
    assert clock.now == 50 * MS


def test_a_transport_closed_by_its_owner_is_dropped() -> None:
    clock, wall, runner, line, _ = _setup()
    closed: list[int] = []
    runner.attach(line, lambda data, now: None, closed.append)
    clock.schedule(10 * MS, lambda now: line.close())
    runner.advance(20 * MS)
    assert closed == [10 * MS]
    assert not runner.paced


def test_listener_connections_are_handed_over_with_their_time() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, speed=2.0, wall=wall)
    listener = FakeListener(fd=20)
    connections: list[tuple[str, int]] = []
    runner.attach_listener(listener, lambda t, now: connections.append((t.name, now)))
    assert runner.paced
    conn = FakeLine(fd=21, name="conn")
    wall.connection_at(0.010, listener, conn)
    runner.advance(100 * MS)
    assert connections == [("conn", 20 * MS)]
    runner.detach(listener)
    assert not runner.paced


class _QueuedLine(FakeLine):
    """A fake real transport with output the kernel has not taken yet."""

    def __init__(self, fd: int) -> None:
        super().__init__(fd)
        self.pending_output = 3
        self.flushes = 0

    def flush(self) -> None:
        self.flushes += 1
        if self.flushes == 4:
            self.pending_output = 0


def test_queued_output_is_flushed_with_short_waits() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, wall=wall)
    line = _QueuedLine(fd=12)
    runner.attach(line, lambda data, now: None)
    runner.advance(S)
    assert line.flushes == 4
    assert wall.waits[:3] == pytest.approx([POLL_WAIT_S] * 3)
    assert wall.waits[3] == pytest.approx(MAX_WAIT_S)  # nothing queued: back to long waits


# ------------------------------------------------------------------ not paced


def test_no_transports_is_the_plain_clock() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, wall=wall)
    log: Log = []
    for at in range(0, 10 * S, 100 * MS):
        _event(clock, at + 1, log)
    runner.advance(10 * S)
    assert len(log) == 100
    assert wall.waits == []
    assert wall.now == START
    assert not runner.paced


def test_memory_transports_are_pumped_between_instants_without_pacing() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, speed=1.0, wall=wall)
    device_side, peer_side = memory_pair()
    echo_a, echo_b = memory_pair()
    log: Log = []
    runner.attach(device_side, lambda data, now: log.append((data.decode(), now)))
    runner.attach(echo_b, lambda data, now: log.append(("echo " + data.decode(), now)))
    peer_side.send(b"before")
    clock.schedule(5 * MS, lambda now: echo_a.send(b"at 5 ms"))
    clock.schedule(5 * MS, lambda now: log.append(("same instant", now)))
    runner.advance(S)
    assert log == [("before", 0), ("same instant", 5 * MS), ("echo at 5 ms", 5 * MS)]
    assert not runner.paced
    assert wall.waits == []
    assert clock.now == S


def test_fastest_polls_between_events_with_zero_timeout() -> None:
    clock, wall, runner, line, log = _setup(speed=None)
    assert not runner.paced
    for at in (1 * S, 2 * S, 3 * S):
        _event(clock, at, log)
    runner.advance(3 * S)
    assert [n for _, n in log] == [1 * S, 2 * S, 3 * S]
    assert wall.waits == [0, 0, 0]
    assert wall.now == START  # three simulated seconds took no wall time


def test_fastest_idle_waits_for_data_with_time_following_the_wall() -> None:
    clock, wall, runner, line, log = _setup(speed=None)
    wall.data_at(0.3, line, b"request")
    runner.advance(2 * S)
    assert log == [("request", 300 * MS)]
    assert all(w is not None and w <= MAX_WAIT_S for w in wall.waits)
    assert clock.now == 2 * S


def test_fastest_delivers_waiting_bytes_at_the_current_instant() -> None:
    clock, wall, runner, line, log = _setup(speed=None)
    _event(clock, 7 * S, log)
    wall.data_at(0.0, line, b"now")
    runner.advance(10 * S)
    assert log[0] == ("now", 0)
    assert log[1] == ("event@7000000", 7 * S)


# ------------------------------------------------------------------ run_until / run_forever


def test_run_until_stops_at_the_instant_the_predicate_holds() -> None:
    clock, wall, runner, line, log = _setup(speed=4.0)
    for at in (10 * MS, 20 * MS, 30 * MS):
        _event(clock, at, log)
    assert runner.run_until(lambda: len(log) == 2, S)
    assert clock.now == 20 * MS
    assert wall.now - START == pytest.approx(0.005)


def test_run_until_stops_after_the_data_that_satisfies_it() -> None:
    clock, wall, runner, line, log = _setup()
    wall.data_at(0.042, line, b"reply")
    assert runner.run_until(lambda: bool(log), S)
    assert clock.now == 42 * MS


def test_run_until_gives_up_at_the_limit() -> None:
    clock, wall, runner, _, _ = _setup()
    assert not runner.run_until(lambda: False, 300 * MS)
    assert clock.now == 300 * MS


def test_run_until_true_at_once_runs_nothing() -> None:
    clock, wall, runner, _, log = _setup()
    _event(clock, 0, log)
    assert runner.run_until(lambda: True, S)
    assert log == [] and wall.waits == []


def test_run_until_without_transports_steps_the_clock() -> None:
    clock = SimClock()
    runner = Runner(clock, wall=FakeWall())
    fired: list[int] = []
    for at in (1 * MS, 2 * MS, 3 * MS):
        clock.schedule(at, fired.append)
    assert runner.run_until(lambda: len(fired) == 2, S)
    assert clock.now == 2 * MS


@pytest.mark.parametrize("speed", [1.0, None])
def test_run_forever_ticks_every_tick_us_until_stop(speed: float | None) -> None:
    clock, wall, runner, _, _ = _setup(speed)
    ticks: list[int] = []
    runner.run_forever(_ticker(runner, ticks, 3), tick_us=100 * MS)
    assert ticks == [100 * MS, 200 * MS, 300 * MS]


def test_run_forever_paced_sleeps_until_each_tick() -> None:
    clock, wall, runner, _, _ = _setup(speed=2.0)
    ticks: list[int] = []
    runner.run_forever(_ticker(runner, ticks, 4), 50 * MS)
    assert ticks == [50 * MS, 100 * MS, 150 * MS, 200 * MS]
    assert wall.now - START == pytest.approx(0.1)


def test_run_forever_returns_on_keyboard_interrupt() -> None:
    clock, wall, runner, _, _ = _setup()

    def interrupt(now: int) -> None:
        raise KeyboardInterrupt

    clock.schedule(70 * MS, interrupt)
    runner.run_forever()
    assert clock.now == 70 * MS


def test_run_forever_with_nothing_to_do_waits_on_the_wall_instead_of_spinning() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, speed=4.0, wall=wall)
    ticks: list[int] = []
    runner.run_forever(_ticker(runner, ticks, 5), S)
    assert ticks == [1 * S, 2 * S, 3 * S, 4 * S, 5 * S]
    assert wall.now - START == pytest.approx(5 / 4)
    assert max(w for w in wall.waits if w is not None) <= MAX_WAIT_S


def test_run_forever_without_transports_runs_busy_events_at_full_speed() -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, wall=wall)
    fired: list[int] = []

    def every_ms(now: int) -> None:
        fired.append(now)
        if len(fired) == 5000:
            runner.stop()
        else:
            clock.call_later(MS, every_ms)

    clock.schedule(MS, every_ms)
    runner.run_forever()
    assert fired[-1] == 5 * S
    assert wall.now == START


# ------------------------------------------------------------------ errors and state


@pytest.mark.parametrize("speed", [0, -1.0, float("nan")])
def test_bad_speed_is_a_config_error(speed: float) -> None:
    with pytest.raises(ConfigError, match="speed"):
        Runner(SimClock(), speed)


def test_bad_durations_are_config_errors() -> None:
    runner = Runner(SimClock(), wall=FakeWall())
    with pytest.raises(ConfigError, match="negative"):
        runner.advance(-1)
    with pytest.raises(ConfigError, match="limit"):
        runner.run_until(lambda: False, -1)
    with pytest.raises(ConfigError, match="tick_us"):
        runner.run_forever(tick_us=0)


def test_attaching_a_closed_transport_is_refused() -> None:
    line = FakeLine(fd=3)
    line.close()
    with pytest.raises(TransportError, match="closed"):
        Runner(SimClock(), wall=FakeWall()).attach(line, lambda data, now: None)


def test_paced_only_with_something_real_and_a_speed() -> None:
    runner = Runner(SimClock(), 1.0, wall=FakeWall())
    a, _ = memory_pair()
    runner.attach(a, lambda data, now: None)
    assert not runner.paced
    line = FakeLine(fd=4)
    runner.attach(line, lambda data, now: None)
    assert runner.paced
    runner.speed = None
    assert not runner.paced
    runner.detach(line)
    runner.detach(line)  # detaching twice is harmless
