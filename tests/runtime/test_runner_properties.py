"""Property: paced runs keep simulated time in step with the (fake) wall and never go back."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, SimClock
from fieldtwin.runtime.runner import Runner
from tests.runtime.fake_wall import START, FakeLine, FakeWall

END = 1000 * MS


def _recorder(log: list[tuple[str, int]], name: str) -> Callable[[int], None]:
    return lambda now: log.append((name, now))


@settings(max_examples=60, deadline=None)
@given(
    speed=st.sampled_from([0.25, 1.0, 3.0, 10.0, 100.0]),
    event_times=st.lists(st.integers(0, END), max_size=20),
    arrivals_ms=st.lists(st.integers(1, 999), max_size=10, unique=True),
)
def test_paced_runs_follow_the_wall_and_never_go_back(
    speed: float, event_times: list[int], arrivals_ms: list[int]
) -> None:
    clock = SimClock()
    wall = FakeWall()
    runner = Runner(clock, speed, wall=wall)
    line = FakeLine(fd=5)
    log: list[tuple[str, int]] = []
    runner.attach(line, lambda data, now: log.append((data.decode(), now)))
    for at in event_times:
        clock.schedule(at, _recorder(log, f"e{at}"))
    for ms in arrivals_ms:
        wall.data_at(ms * MS / 1e6 / speed, line, f"d{ms}".encode())
    runner.advance(END)

    times = [now for _, now in log]
    assert times == sorted(times)  # simulated time never goes back
    events = [(name, now) for name, now in log if name.startswith("e")]
    assert sorted(events) == sorted((f"e{t}", t) for t in event_times)  # each at its own time
    data = [(name, now) for name, now in log if name.startswith("d")]
    for name, now in data:
        assert now == pytest.approx(int(name[1:]) * MS, abs=1)  # arrival time, to the microsecond
    assert len(data) == len(arrivals_ms)
    assert clock.now == END
    assert wall.now - START == pytest.approx(END / 1e6 / speed)
