"""Reads that change nothing come from the snapshot the simulation published, without a
hop onto its thread; a read sent after a command's answer sees that command's effect."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass

import httpx
import pytest

from fieldtwin.client import Client
from fieldtwin.control.resources import Control
from fieldtwin.control.server import ControlServer, bind_control
from fieldtwin.control.sim import serve
from fieldtwin.control.snapshot import Snapshot
from fieldtwin.plant import build_plant, read_plant
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.runner import Runner

WAIT_S = 10.0


def test_a_value_is_current_until_a_change_or_its_age() -> None:
    wall = [100.0]
    snapshot = Snapshot(max_age_s=0.005, now=lambda: wall[0])
    made: list[int] = []
    assert snapshot.get("clock") is None
    assert snapshot.take("clock", lambda: made.append(1) or {"t": 1}) == {"t": 1}
    assert snapshot.get("clock") == {"t": 1}
    wall[0] += 0.005
    assert snapshot.get("clock") == {"t": 1}  # at its age: still current
    wall[0] += 0.0001
    assert snapshot.get("clock") is None  # older
    snapshot.take("clock", lambda: {"t": 2})
    snapshot.changed()  # a command ran
    assert snapshot.get("clock") is None
    assert made == [1]


def test_while_a_refresh_is_under_way_a_recent_value_serves_until_a_change() -> None:
    wall = [100.0]
    snapshot = Snapshot(max_age_s=0.005, now=lambda: wall[0], refreshing_s=0.05)
    assert snapshot.recent("clock") is None
    snapshot.take("clock", lambda: {"t": 1})
    wall[0] += 0.02
    assert snapshot.get("clock") is None  # too old to be current: a refresh is due
    assert snapshot.recent("clock") == {"t": 1}  # what readers take while it runs
    wall[0] += 0.0301
    assert snapshot.recent("clock") is None  # older than refreshing_s
    snapshot.take("clock", lambda: {"t": 2})
    snapshot.changed()  # a command ran: read-your-writes, never the value before it
    assert snapshot.recent("clock") is None


def test_a_read_that_fails_publishes_nothing() -> None:
    snapshot = Snapshot()

    def missing() -> int:
        raise KeyError("no device")

    with pytest.raises(KeyError):
        snapshot.take("status", missing)
    assert snapshot.get("status") is None


@dataclass
class InProcess:
    url: str
    control: Control
    serving: threading.Event  # cleared: the simulation's thread takes no command
    idle: threading.Event  # set once it has seen that (its last command counted)
    hops: list[int]


@pytest.fixture
def plant() -> Iterator[InProcess]:
    """The default plant, its commands taken by a thread of ours (counted, and held
    while ``serving`` is clear); its snapshot values never too old by the wall."""
    built = build_plant(read_plant(None))
    inbox = Inbox(door=built.door)  # commands are values the plant's door runs
    control = Control(built, Runner(built.clock, None), EventBus())
    serve(built.door, control, control.console.handle)
    control.snapshot.max_age_s = 3600.0  # only a change makes a value stale here
    server = ControlServer(control, inbox, bind_control("127.0.0.1", 0, fallback=False), None)
    stop, serving, idle, hops = threading.Event(), threading.Event(), threading.Event(), [0]
    serving.set()

    def take() -> None:
        while not stop.is_set():
            if not serving.is_set():
                idle.set()
                serving.wait(0.05)
                continue
            idle.clear()
            if inbox.wait(0.05):
                hops[0] += inbox.run_pending()

    thread = threading.Thread(target=take, daemon=True)
    thread.start()
    try:
        yield InProcess(server.start(), control, serving, idle, hops)
    finally:
        stop.set()
        thread.join(WAIT_S)
        server.close()
        inbox.close()


def test_a_published_read_is_answered_while_the_simulation_takes_no_command(
    plant: InProcess,
) -> None:
    with httpx.Client(base_url=plant.url, timeout=WAIT_S) as http:
        paths = ["/clock", "/devices/tes1", "/devices/tes1/leds", "/dashboard/state"]
        first = {path: http.get(path).json() for path in paths}
        plant.serving.clear()  # the simulation's thread is busy: no command runs
        assert plant.idle.wait(WAIT_S)
        hops = plant.hops[0]
        for path in paths:
            assert http.get(path).json() == first[path]
        assert plant.hops[0] == hops  # not one hop
        plant.serving.set()


def test_a_read_after_a_commands_answer_sees_its_effect(plant: InProcess) -> None:
    with Client(plant.url, timeout_s=WAIT_S) as client:
        for value in (0x1234, 0x0042, 0xBEEF):
            before = client.peek("tes1", "H'00C'")  # published: the next peek may use it
            assert client.peek("tes1", "H'00C'") == before
            assert client.write("tes1", "H'00C'", value) == value
            assert client.peek("tes1", "H'00C'") == value
        assert client.clock()["paused"] is False
        client.pause()
        assert client.clock()["paused"] is True
        client.resume()
        assert client.clock()["paused"] is False
        assert client.status("tes1")["active_faults"] == {}
        client.set_fault("tes1", "late_answer", ms=200)
        assert client.status("tes1")["active_faults"] == {"late_answer": {"ms": 200}}
        assert [f["active"] for f in client.faults("tes1") if f["name"] == "late_answer"] == [True]
        client.clear_fault("tes1", "late_answer")
        assert client.status("tes1")["active_faults"] == {}
