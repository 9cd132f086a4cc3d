"""Issue 10 items 1-3 in the runner: failed accepts, O(1) attachments, bounded output."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import textwrap
import time

from fieldtwin.clock import MS, SimClock
from fieldtwin.runtime.runner import ACCEPT_BACKOFF_S, OUTPUT_BOUND, Runner
from fieldtwin.runtime.wall import SystemWall
from fieldtwin.transports.base import AcceptFailed, Transport
from fieldtwin.transports.tcp import TCP_READ_CHUNK, connect, listen
from tests.runtime.fake_wall import FakeLine, FakeListener, FakeWall

DEADLINE_S = 20.0


class _CountingWall(FakeWall):
    def __init__(self) -> None:
        super().__init__()
        self.watches = 0
        self.forgets = 0

    def watch(self, fd: int, read: bool = True, write: bool = False) -> None:
        self.watches += 1
        super().watch(fd, read, write)

    def forget(self, fd: int) -> None:
        self.forgets += 1
        super().forget(fd)


def test_attaching_and_detaching_touch_only_that_descriptor() -> None:
    wall = _CountingWall()
    runner = Runner(SimClock(), wall=wall)
    lines = [FakeLine(fd=100 + i) for i in range(500)]
    for line in lines:
        runner.attach(line, lambda data, now: None)
    assert wall.watches == 500 and wall.fds == {100 + i for i in range(500)}
    runner.advance(10 * MS)
    runner.detach(lines[7])
    assert wall.forgets == 1 and 107 not in wall.fds and len(wall.fds) == 499
    runner.advance(10 * MS)
    assert wall.watches == 500  # nothing re-registered by the waits


class _FailingListener(FakeListener):
    """Accept fails ``failures`` times (as EMFILE would), then works."""

    def __init__(self, fd: int, failures: int) -> None:
        super().__init__(fd)
        self.failures = failures
        self.calls = 0

    def accept(self) -> Transport | None:
        self.calls += 1
        if self.failures:
            self.failures -= 1
            raise AcceptFailed("tcp://127.0.0.1:1: cannot accept a connection: [Errno 24]")
        return super().accept()


def test_a_failed_accept_backs_off_reports_once_and_keeps_serving() -> None:
    clock, wall, reports = SimClock(), FakeWall(), []
    runner = Runner(clock, wall=wall, report=reports.append)
    listener = _FailingListener(fd=20, failures=5)
    accepted: list[Transport] = []
    runner.attach_listener(listener, lambda t, now: accepted.append(t))
    served = FakeLine(fd=21)
    got: list[bytes] = []
    runner.attach(served, lambda data, now: got.append(data))
    newcomer = FakeLine(fd=22)
    wall.connection_at(0.01, listener, newcomer)
    for i in range(10):
        wall.data_at(0.02 + i * 0.05, served, b"x")
    runner.advance(600 * MS)
    assert got == [b"x"] * 10  # the open connection never stopped being served
    assert accepted == [newcomer]  # taken once the backoff let the listener be tried again
    # 5 failures spaced by a doubling backoff (not a busy loop), the newcomer, then "nobody"
    assert listener.calls == 7
    assert len(reports) == 2
    assert "cannot accept" in reports[0] and "still served" in reports[0]
    assert reports[1].endswith("accepting connections again")
    assert wall.now - 1000.0 >= ACCEPT_BACKOFF_S * (1 + 2 + 4 + 8)


def test_the_connection_limit_closes_extra_connections_at_once() -> None:
    runner = Runner(SimClock(), speed=None)
    listener = listen("127.0.0.1", 0, max_connections=2)
    accepted: list[Transport] = []
    runner.attach_listener(listener, lambda t, now: accepted.append(t))
    host, port = listener.address
    clients = [socket.create_connection((host, port), timeout=5) for _ in range(3)]
    try:
        runner.run_until(lambda: len(accepted) + listener.refused >= 3, 2000 * MS)
        assert len(accepted) == 2 and listener.refused == 1 and listener.live == 2
        clients[2].settimeout(5)
        with contextlib.suppress(ConnectionResetError):  # closed at once: FIN or RST
            assert clients[2].recv(1) == b""
        accepted[0].close()
        assert listener.live == 1  # a slot is free again
    finally:
        for c in clients:
            c.close()
        for t in accepted:
            t.close()
        listener.close()


def test_a_peer_that_never_reads_stops_being_read_and_others_are_served() -> None:
    runner = Runner(SimClock(), speed=None)
    listener = listen("127.0.0.1", 0)
    conns: list[Transport] = []

    def on_connect(t: Transport, now: int) -> None:
        conns.append(t)
        runner.attach(t, lambda data, now: t.send(data * 8))  # answers 8x what it hears

    runner.attach_listener(listener, on_connect)
    host, port = listener.address
    mute = socket.create_connection((host, port), timeout=5)
    mute.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    mute.setblocking(False)
    fast = connect(host, port)
    try:
        runner.run_until(lambda: len(conns) == 2, 2000 * MS)
        sent, deadline = 0, time.monotonic() + DEADLINE_S
        while time.monotonic() < deadline:
            try:
                sent += mute.send(b"r" * 4096)
            except BlockingIOError:
                runner.advance(5 * MS)
                try:
                    sent += mute.send(b"r" * 4096)
                except BlockingIOError:
                    break  # the twin no longer reads it: TCP holds the peer back
            runner.advance(1 * MS)
        assert time.monotonic() < deadline
        queued = max(getattr(t, "pending_output", 0) for t in conns)
        assert queued <= OUTPUT_BOUND + 8 * TCP_READ_CHUNK  # the bound plus one read's answers
        got = bytearray()
        fast.send(b"ping")
        runner.run_until(lambda: bool(got.extend(fast.receive()) or len(got) >= 32), 2000 * MS)
        assert bytes(got) == b"ping" * 8
    finally:
        mute.close()
        fast.close()
        for t in conns:
            t.close()
        listener.close()


def test_system_wall_watches_incrementally() -> None:
    wall = SystemWall()
    r, w = os.pipe()
    try:
        wall.watch(r)
        wall.watch(w, read=False, write=True)
        assert wall.watched == 2
        readable, writable = wall.wait(1.0)
        assert list(readable) == [] and list(writable) == [w]
        wall.watch(w, read=False, write=False)
        assert wall.watched == 1
        wall.forget(r)
        wall.forget(r)  # twice: ignored
        assert wall.watched == 0
    finally:
        wall.close()
        os.close(r)
        os.close(w)


SERVER = textwrap.dedent(
    """
    import resource, sys
    from fieldtwin.clock import SimClock
    from fieldtwin.runtime.runner import Runner
    from fieldtwin.transports.tcp import listen
    resource.setrlimit(resource.RLIMIT_NOFILE, (64, 64))
    runner = Runner(SimClock())
    listener = listen("127.0.0.1", 0)
    def on_connect(t, now):
        runner.attach(t, lambda data, now: t.send(data))
    runner.attach_listener(listener, on_connect)
    print(listener.address[1], flush=True)
    runner.advance(int(float(sys.argv[1]) * 1_000_000))
    print("done", flush=True)
    """
)


def test_running_out_of_descriptors_never_ends_the_server() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", SERVER, "4"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    clients: list[socket.socket] = []
    try:
        assert proc.stdout is not None and proc.stderr is not None
        port = int(proc.stdout.readline())
        first = socket.create_connection(("127.0.0.1", port), timeout=5)
        first.sendall(b"a")
        assert first.recv(1) == b"a"
        for _ in range(100):  # far more than 64 descriptors
            clients.append(socket.create_connection(("127.0.0.1", port), timeout=5))
        for i in range(5):
            first.sendall(b"%d" % i)
            assert first.recv(1) == b"%d" % i  # the open connection is still served
        for c in clients:
            c.close()
        clients.clear()
        assert proc.stdout.readline() == "done\n"  # ran to its end: never exited on EMFILE
        assert proc.wait(timeout=DEADLINE_S) == 0
        err = proc.stderr.read()
        assert err.count("cannot accept") == 1, err
        assert "Too many open files" in err
    finally:
        for c in clients:
            c.close()
        proc.kill()
        proc.wait(timeout=DEADLINE_S)
