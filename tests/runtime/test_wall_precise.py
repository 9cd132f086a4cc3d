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

    class Fake:  # a test wall without the ability
        pass

    Runner(SimClock(), speed=1.0, wall=Fake()).want_precise_waits(True)  # type: ignore[arg-type]
