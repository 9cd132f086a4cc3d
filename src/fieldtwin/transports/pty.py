"""A pseudo-terminal: the twin holds the master, a peer opens ``peer_path``.

A peer (a SCADA driver, picocom, a pyserial script) opens the slave path as if
it were a serial port: ``serial.Serial(transport.peer_path, timeout=1)``.

* Both ends are put in raw mode (no echo, no line editing, 8-bit clean).
* The master is non-blocking; writes the kernel will not take are queued.
* We keep our own descriptor on the slave open, so the pty never hangs up when
  a peer closes and reopens it (the master would otherwise read EIO).  We
  never read from that descriptor, so nothing meant for the peer is consumed.

termios and tty are imported when a pty is opened, not with this module: the rest of
the package (a TCP-only plant, the console) runs where they do not exist (README,
"POSIX").
"""

from __future__ import annotations

import os

from fieldtwin.transports.base import READ_CHUNK, FdTransport, LineSettings, line_settings


def _apply_speed(fd: int, baud: int) -> None:
    """Record the baud rate in the termios of ``fd`` (cosmetic on a pty; peers may read it)."""
    import termios

    speed = getattr(termios, f"B{baud}", None)
    if speed is None:
        return  # a non-standard rate: a pty does not care; char_time_us still uses it
    attrs = termios.tcgetattr(fd)
    attrs[4] = attrs[5] = speed
    termios.tcsetattr(fd, termios.TCSANOW, attrs)


class PtyTransport(FdTransport):
    """The master side of a pty pair."""

    def __init__(self, settings: LineSettings | None = None) -> None:
        import tty  # here: see the module's docstring

        master, slave = os.openpty()
        try:
            tty.setraw(master)
            tty.setraw(slave)
            self.settings = settings or line_settings()
            _apply_speed(slave, self.settings.baud)
            os.set_blocking(master, False)
            path = os.ttyname(slave)
        except BaseException:
            os.close(master)
            os.close(slave)
            raise
        super().__init__(f"pty:{path}")
        self.peer_path = path
        self._master = master
        self._slave = slave

    def _write(self, data: bytes) -> int:
        return os.write(self._master, data)

    def receive(self) -> bytes:
        """What the peer has written since the last call; b"" if nothing."""
        self._check_open("receive")
        self.flush()
        try:
            return os.read(self._master, READ_CHUNK)
        except BlockingIOError:
            return b""
        except OSError as exc:
            self._broken(f"read failed: {exc}")
            raise  # pragma: no cover - _broken always raises

    def fileno(self) -> int | None:
        return None if self.closed else self._master

    def _release(self) -> None:
        os.close(self._master)
        os.close(self._slave)


def open_pty(settings: LineSettings | None = None) -> PtyTransport:
    """A new pty; give ``.peer_path`` to whoever plays the other end."""
    return PtyTransport(settings)
