"""The one small transport interface every backend implements (DESIGN rule 5).

A transport moves bytes, nothing else: it never blocks the simulation, never
frames, never reads the simulated clock.  ``send`` queues what the kernel will
not take at once and flushes it on the next ``send``, ``receive`` or ``flush``;
``receive`` returns what has arrived (``b""`` when nothing has).

Learned from python-can's bus/interface split and httpcore's thin adapters.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NoReturn, Protocol, runtime_checkable

from fieldtwin.charformat import CharFormat
from fieldtwin.charformat import line_settings as line_settings  # re-exported
from fieldtwin.errors import TransportError

DATA_BITS = (7, 8)
PARITIES = ("N", "E", "O")
STOP_BITS = (1, 2)
READ_CHUNK = 65536

# The serial character format of a transport is the kernel's one value
# (issue 9 item 3).  ``LineSettings`` stays as its name here for the code that
# imports it; ``line_settings`` builds one from the usual letters ("8E1").
LineSettings = CharFormat


class AcceptFailed(TransportError):
    """A listener could not take a waiting connection for want of resources
    (EMFILE, ENFILE, ENOBUFS, ENOMEM): the runner backs off and retries."""


class TransportWatcher(Protocol):
    """Told by an fd-backed transport when output stays queued and when it closes."""

    def backlogged(self, transport: FdTransport) -> None: ...

    def closed(self, transport: FdTransport) -> None: ...


class Transport(Protocol):
    """A byte pipe to one peer (see module docstring for the rules)."""

    name: str
    peer_path: str | None
    is_real: bool
    closed: bool

    def send(self, data: bytes) -> None: ...

    def receive(self) -> bytes: ...

    def fileno(self) -> int | None: ...

    def close(self) -> None: ...


SendObserver = Callable[[bytes], None]


@runtime_checkable
class SendObservable(Protocol):
    """A transport that tells one observer every send (a recording, a replay: the
    runner's attach tap gives it): ``observe_sends(None)`` stops it."""

    def observe_sends(self, observer: SendObserver | None) -> None: ...


class Listener(Protocol):
    """A listening socket: ``accept`` hands out connected transports."""

    name: str
    address: tuple[str, int]

    def accept(self) -> Transport | None: ...

    def fileno(self) -> int: ...

    def close(self) -> None: ...


@runtime_checkable
class Flushable(Protocol):
    """What our own transports add: bytes queued for the kernel, and a way to push them."""

    @property
    def pending_output(self) -> int: ...

    def flush(self) -> None: ...


class FdTransport:
    """Shared body of the fd-backed transports (pty, serial, TCP): an output queue over
    ``_write`` (os.write, or socket.send), flushed as far as the kernel takes it."""

    is_real = True
    peer_path: str | None = None

    def __init__(self, name: str) -> None:
        self.name = name
        self.closed = False
        self._out = bytearray()
        # the runner that pumps this transport, told of queued output and of the close
        self.watcher: TransportWatcher | None = None
        self._sends: SendObserver | None = None  # sees every send (observe_sends)

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<{type(self).__name__} {self.name} {state}>"

    @property
    def pending_output(self) -> int:
        return len(self._out)

    def _check_open(self, what: str) -> None:
        if self.closed:
            raise TransportError(f"cannot {what} on {self.name}: it is closed")

    def observe_sends(self, observer: SendObserver | None) -> None:
        """``observer(data)`` sees every send from now on (None: none any more)."""
        self._sends = observer

    def send(self, data: bytes) -> None:
        """Queue ``data`` and write as much as the kernel takes now."""
        self._check_open("send")
        if self._sends is not None:
            self._sends(data)
        if not self._out and len(data) <= READ_CHUNK:
            # nothing queued (the usual case): write at once, queue what is left
            written = self._write_some(data)
            if written >= len(data):
                return
            self._out += data[max(written, 0) :]
        else:
            self._out += data
            self.flush()
        if self._out and self.watcher is not None:
            self.watcher.backlogged(self)

    def flush(self) -> None:
        """Write queued bytes until the kernel would block."""
        out = self._out
        while out and not self.closed:
            written = self._write_some(bytes(out[:READ_CHUNK]))
            if written <= 0:
                return
            del out[:written]

    def _write_some(self, data: bytes) -> int:
        """``_write``: the bytes the kernel took, 0 when it would block."""
        try:
            return self._write(data)
        except BlockingIOError:
            return 0
        except OSError as exc:
            self._broken(f"write failed: {exc}")

    def _broken(self, why: str) -> NoReturn:
        self.close()
        raise TransportError(f"{self.name}: {why}")

    def _write(self, data: bytes) -> int:
        raise NotImplementedError

    def fileno(self) -> int | None:
        raise NotImplementedError

    def receive(self) -> bytes:
        raise NotImplementedError

    def close(self) -> None:
        """Close once: tell the watcher first (it forgets the fd before it is reused)."""
        if self.closed:
            return
        watcher, self.watcher = self.watcher, None
        if watcher is not None:
            watcher.closed(self)
        self.closed = True
        self._out.clear()
        self._release()

    def _release(self) -> None:
        raise NotImplementedError
