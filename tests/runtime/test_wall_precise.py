"""Issue 15 item 2: precise waits of the system wall (no timing asserted: readiness only)."""

from __future__ import annotations

import os

from fieldtwin.clock import SimClock
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wall import SystemWall


def test_precise_waits_are_counted_and_return_a_ready_descriptor_at_once() -> None:
    wall = SystemWall()
    read, write = os.pipe()
    try:
        wall.watch(read)
        assert not wall.precise
        wall.want_precision(True)
        wall.want_precision(True)
        wall.want_precision(False)
        assert wall.precise
        os.write(write, b"x")
        readable, _ = wall.wait(10.0)  # ready: returns without waiting the timeout out
        assert list(readable) == [read]
        wall.want_precision(False)
        wall.want_precision(False)  # never below zero
        assert not wall.precise
    finally:
        wall.close()
        os.close(read)
        os.close(write)


def test_the_runner_passes_the_wish_on_and_a_fake_wall_ignores_it() -> None:
    wall = SystemWall()
    runner = Runner(SimClock(), speed=1.0, wall=wall)
    runner.want_precise_waits(True)
    assert wall.precise
    runner.want_precise_waits(False)
    assert not wall.precise

    from tests.runtime.fake_wall import FakeWall

    # a test wall without the ability: its typed want_precision ignores the wish
    Runner(SimClock(), speed=1.0, wall=FakeWall()).want_precise_waits(True)


def test_the_system_wall_leads_only_while_precise_waits_are_wanted() -> None:
    from fieldtwin.runtime.wall import PRECISE_LEAD_S

    wall = SystemWall()
    try:
        assert wall.lead_s == 0.0
        wall.want_precision(True)
        assert wall.lead_s == PRECISE_LEAD_S > 0
        wall.want_precision(False)
        assert wall.lead_s == 0.0
    finally:
        wall.close()


def test_a_wall_with_a_lead_has_a_due_instant_run_that_much_wall_time_early() -> None:
    """A wire-timed reply reaches a pty's master when its instant comes: the runner
    runs the instant the wall's lead early (docs/modbus.md, "Wire timing")."""
    from fieldtwin.clock import MS
    from tests.runtime.fake_wall import START, FakeLine, FakeWall

    class LeadingWall(FakeWall):
        lead_s = 0.00025

    for wall, early in ((FakeWall(), 0.0), (LeadingWall(), 0.00025)):
        clock = SimClock()
        runner = Runner(clock, speed=1.0, wall=wall)
        runner.attach(FakeLine(fd=30), lambda data, now: None)  # a real line: paced
        ran: list[tuple[int, float]] = []
        clock.schedule(10 * MS, lambda now, w=wall, r=ran: r.append((now, w.now - START)))
        runner.advance(20 * MS)
        assert ran[0][0] == 10 * MS  # the same instant in simulated time
        assert abs(ran[0][1] - (0.010 - early)) < 1e-9  # run at its wall time, minus the lead
        assert clock.now == 20 * MS
