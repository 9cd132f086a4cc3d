"""The runner against real ptys and sockets (loose bounds only, never tight timing)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator

import pytest
import serial

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wall import SystemWall
from fieldtwin.transports.base import Transport
from fieldtwin.transports.pty import PtyTransport, open_pty
from fieldtwin.transports.tcp import connect, listen


@pytest.fixture
def pty() -> Iterator[PtyTransport]:
    transport = open_pty()
    yield transport
    transport.close()


def test_bytes_typed_by_a_pyserial_peer_are_delivered_and_answered(pty: PtyTransport) -> None:
    clock = SimClock()
    runner = Runner(clock, speed=10.0)
    got: list[tuple[bytes, int]] = []
    runner.attach(pty, lambda data, now: got.append((data, now)))
    clock.schedule(100 * MS, lambda now: pty.send(b"answer at 100 ms"))
    assert pty.peer_path is not None
    with serial.Serial(pty.peer_path, timeout=2) as peer:
        peer.write(b"typed")
        start = time.monotonic()
        runner.advance(200 * MS)
        elapsed = time.monotonic() - start
        assert b"".join(data for data, _ in got) == b"typed"
        assert all(0 <= now <= 200 * MS for _, now in got)
        assert peer.read(16) == b"answer at 100 ms"
    assert runner.paced
    assert clock.now == 200 * MS
    assert elapsed < 2.0  # 0.2 s simulated at x10 is about 0.02 s of wall


def test_fastest_mode_waits_for_a_real_peer(pty: PtyTransport) -> None:
    clock = SimClock()
    runner = Runner(clock, speed=None)
    got: list[bytes] = []
    runner.attach(pty, lambda data, now: got.append(data))
    assert pty.peer_path is not None
    with serial.Serial(pty.peer_path, timeout=2) as peer:
        peer.write(b"\x01\x03")
        assert runner.run_until(lambda: b"".join(got) == b"\x01\x03", 5 * S)


def test_a_tcp_client_is_accepted_and_heard() -> None:
    clock = SimClock()
    runner = Runner(clock, speed=10.0)
    listener = listen()
    accepted: list[Transport] = []
    heard: list[bytes] = []

    def on_connect(transport: Transport, now: int) -> None:
        accepted.append(transport)
        runner.attach(
            transport, lambda data, now: heard.append(data), lambda now: heard.append(b"<closed>")
        )

    runner.attach_listener(listener, on_connect)
    client = connect(*listener.address)
    try:
        client.send(b"MBAP")
        assert runner.run_until(lambda: b"".join(heard) == b"MBAP", 20 * S)
        client.close()
        assert runner.run_until(lambda: heard[-1] == b"<closed>", 20 * S)
    finally:
        client.close()
        listener.close()
        for transport in accepted:
            transport.close()


def test_system_wall_reregisters_when_the_fd_set_changes() -> None:
    wall = SystemWall()
    try:
        r1, w1 = os.pipe()
        wall.watch(r1)
        assert list(wall.wait(0)[0]) == []
        os.write(w1, b"x")
        assert list(wall.wait(5.0)[0]) == [r1]
        wall.forget(r1)
        os.close(r1)
        os.close(w1)
        r2, w2 = os.pipe()  # likely the same numbers again
        os.write(w2, b"y")
        wall.watch(r2)
        assert list(wall.wait(5.0)[0]) == [r2]  # forgotten, then registered afresh
        wall.forget(r2)
        os.close(r2)
        os.close(w2)
        start = wall.monotonic()
        assert list(wall.wait(0.01)[0]) == []  # nothing registered: a bounded sleep
        assert wall.monotonic() >= start
    finally:
        wall.close()
