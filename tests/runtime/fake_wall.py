"""A scripted wall clock and fake real transports: the runner's pacing, checked without sleeping."""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field

from fieldtwin.errors import TransportError
from fieldtwin.transports.base import Transport

START = 1000.0  # an arbitrary wall time, in seconds


class FakeLine:
    """A transport that looks real (has an fd) and whose bytes arrive at scripted wall times."""

    is_real = True
    peer_path: str | None = None

    def __init__(self, fd: int, name: str = "fake") -> None:
        self.name = name
        self.closed = False
        self.hung_up = False
        self.sent: list[bytes] = []
        self._fd = fd
        self._inbox = bytearray()

    def send(self, data: bytes) -> None:
        if self.closed:
            raise TransportError(f"{self.name} is closed")
        self.sent.append(data)

    def receive(self) -> bytes:
        if self.closed:
            raise TransportError(f"{self.name} is closed")
        data = bytes(self._inbox)
        self._inbox.clear()
        if not data and self.hung_up:
            self.closed = True
            raise TransportError(f"{self.name}: the peer has closed")
        return data

    def fileno(self) -> int | None:
        return None if self.closed else self._fd

    def close(self) -> None:
        self.closed = True

    def arrive(self, data: bytes) -> None:
        if data:
            self._inbox += data
        else:
            self.hung_up = True

    @property
    def readable(self) -> bool:
        return bool(self._inbox) or self.hung_up


class FakeListener:
    """A listener whose connections arrive at scripted wall times."""

    def __init__(self, fd: int) -> None:
        self.name = "fake-listener"
        self.address = ("127.0.0.1", 1)
        self.waiting: list[Transport] = []
        self._fd = fd

    def accept(self) -> Transport | None:
        return self.waiting.pop(0) if self.waiting else None

    def fileno(self) -> int:
        return self._fd

    def close(self) -> None:
        self.waiting.clear()

    @property
    def readable(self) -> bool:
        return bool(self.waiting)


@dataclass(order=True)
class _Arrival:
    at: float
    seq: int
    target: FakeLine | FakeListener = field(compare=False)
    data: bytes | Transport = field(compare=False)


class FakeWall:
    """The runner's WallClock: ``wait`` jumps the fake time instead of sleeping."""

    # the wall's abilities (fieldtwin.runtime.wall.WallClock): none by default; the
    # tests of fast polls and of the lead set their own
    fast_poll_s = 0.0
    lead_s = 0.0

    def want_precision(self, on: bool) -> None:
        """A fake wall cannot wait more precisely than it does: the wish is ignored."""

    def __init__(self) -> None:
        self.now = START
        self.waits: list[float | None] = []
        self.called_at: list[float] = []  # the fake time of every wait: when the runner looked
        self._arrivals: list[_Arrival] = []
        self._targets: list[FakeLine | FakeListener] = []
        self.fds: set[int] = set()  # what the runner watches for reading

    def watch(self, fd: int, read: bool = True, write: bool = False) -> None:
        if read:
            self.fds.add(fd)
        else:
            self.fds.discard(fd)

    def forget(self, fd: int) -> None:
        self.fds.discard(fd)

    def monotonic(self) -> float:
        return self.now

    def spend(self, seconds: float) -> None:
        """A slow callback: the wall moves on while the simulation computes."""
        self.now += seconds

    def data_at(self, at: float, line: FakeLine, data: bytes) -> None:
        """``data`` reaches ``line`` at wall time START + at (b"" = the peer hangs up)."""
        self._targets.append(line)
        self._arrivals.append(_Arrival(START + at, len(self._arrivals), line, data))
        self._arrivals.sort()

    def connection_at(self, at: float, listener: FakeListener, transport: Transport) -> None:
        self._targets.append(listener)
        self._arrivals.append(_Arrival(START + at, len(self._arrivals), listener, transport))
        self._arrivals.sort()

    def _land(self) -> None:
        while self._arrivals and self._arrivals[0].at <= self.now:
            arrival = self._arrivals.pop(0)
            if isinstance(arrival.target, FakeLine):
                assert isinstance(arrival.data, bytes)
                arrival.target.arrive(arrival.data)
            else:
                assert not isinstance(arrival.data, bytes)
                arrival.target.waiting.append(arrival.data)

    def wait(self, timeout: float | None) -> tuple[Collection[int], Collection[int]]:
        fds = self.fds
        assert timeout is None or timeout >= 0, f"negative wait {timeout}"
        self.waits.append(timeout)
        self.called_at.append(self.now)
        pending = [a for a in self._arrivals if a.target.fileno() in fds]
        if pending and (timeout is None or pending[0].at <= self.now + timeout):
            self.now = max(self.now, pending[0].at)
        else:
            assert timeout is not None, "the runner would block forever"
            self.now += timeout
        self._land()
        return self._ready(fds), ()

    def _ready(self, fds: Collection[int]) -> list[int]:
        return [fd for fd in fds if any(t.fileno() == fd and t.readable for t in self._targets)]
