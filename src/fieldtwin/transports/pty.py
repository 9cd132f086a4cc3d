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

Even parity and the "parked" pty (issue 23 item 2).  Linux's pty driver keeps no
parity and no character size: every termios change on a pty clears PARENB and
forces CS8 (drivers/tty/pty.c, ``pty_set_termios``).  The C library of Debian 12
(glibc 2.36 with a distribution patch, as Fedora's; seen in its machine code)
wraps every ``tcsetattr`` in a ``TCGETS`` before and after: when none of the flag
words (c_iflag, c_oflag, c_cflag with the speed, c_lflag) nor c_line changed while
the call asked for a parity (or a size) the result lacks, it fails with EINVAL -
pyserial's ``termios.error: (22, 'Invalid argument')``.  c_cc (VMIN, VTIME) does
not count as a change.  So a master opening a pty with ``parity='E'`` failed
exactly when the pty already held what it asked for apart from the parity (the
same speed: the twin's own line speed, written here, or what a previous master
left), and worked when its open changed the speed.  The twin therefore keeps its
pty *parked*: IXANY set in the input flags (harmless: the pty has no IXON flow
control, and every serial library clears it), so the master's configuration
always changes something and glibc never complains.  ``peer_line`` reads what the
master set and parks the pty again; it is looked at each time bytes arrive
(``receive``), and a change is told to the line's observer (a recording keeps it
as an input, so that a replay reproduces a mismatch).

What no twin can fix: a master that changes a setting of the port it has just
opened with parity (pyserial's ``timeout`` or ``inter_byte_timeout`` setters,
pymodbus's ``connect()``) makes a call that changes no flag word, and fails.  The
twin cannot re-park the pty between the master's two calls (microseconds apart;
nothing in a pty signals a termios change deterministically), and no termios
setting makes the kernel change a flag word on each call: locked bits
(TIOCSLCKTRMIOS) keep their old value.  docs/transports.md says how each master
opens at 8E1.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

from fieldtwin.charformat import CharFormat, Parity
from fieldtwin.transports.base import READ_CHUNK, FdTransport, LineSettings, line_settings


@dataclass(frozen=True, slots=True)
class PeerLine:
    """What a pty shows of its master's line settings: speed, stop bits, odd parity.

    Even parity and none look the same on a Linux pty (the driver clears PARENB),
    and so do 7 and 8 data bits (it forces CS8).
    """

    baud: int | None  # None: a rate termios has no constant for (BOTHER)
    stop_bits: int
    odd: bool

    def seen_as(self, own: CharFormat) -> CharFormat | None:
        """The master's format, with what a pty hides taken from ``own``; None: unknown speed."""
        if self.baud is None:
            return None
        if self.odd:
            parity = Parity.ODD
        else:
            parity = Parity.NONE if own.parity is Parity.NONE else Parity.EVEN
        return CharFormat(self.baud, own.data_bits, parity, self.stop_bits)

    def differs(self, own: CharFormat) -> bool:
        """A UART at ``own`` would not read this master's characters: speed or parity.

        Stop bits are not compared: a UART checks one stop bit, so a second is idle line.
        """
        return self.baud != own.baud or self.odd != (own.parity is Parity.ODD)


LineObserver = Callable[["PeerLine"], None]


@cache
def _speeds() -> dict[int, int]:
    import termios

    out = {}
    for name in dir(termios):
        if name.startswith("B") and name[1:].isdigit():
            out[getattr(termios, name)] = int(name[1:])
    return out


def _park(fd: int) -> None:
    """Set IXANY on ``fd`` (see the module's docstring): a master's next change shows."""
    import termios

    attrs = termios.tcgetattr(fd)
    if not attrs[0] & termios.IXANY:
        attrs[0] |= termios.IXANY
        termios.tcsetattr(fd, termios.TCSANOW, attrs)


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
            _park(slave)
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

    # --- the master's line settings (runtime/uart.py reads them, a recording keeps them)

    _line_news: PeerLine | None = None  # class defaults: a replay's pty skips __init__
    _line_observer: LineObserver | None = None

    def observe_line(self, observer: LineObserver | None) -> None:
        """Call ``observer`` with every change of the master's settings (a recording's
        ``settings`` input), when it is seen: before the bytes that follow it."""
        self._line_observer = observer

    def note_line(self, line: PeerLine) -> None:
        """The master set ``line``: read from the pty, or a replay's recorded input."""
        self._line_news = line
        if self._line_observer is not None:
            self._line_observer(line)

    def peer_line(self) -> PeerLine | None:
        """The settings the master set since the last call; None: no change.

        The pty is looked at when bytes arrive (``receive``), never here: so every
        change a device acts on was seen, in order, by whoever observes the line.
        """
        news, self._line_news = self._line_news, None
        return news

    def _look_at_line(self) -> None:
        """Read the master's settings if it changed them, and park the pty again."""
        slave = getattr(self, "_slave", None)  # a replay's pty has none: nothing to see
        if slave is None:
            return
        import termios

        try:
            attrs = termios.tcgetattr(slave)
            if attrs[0] & termios.IXANY:
                return  # still parked: the master changed nothing
            cflag = attrs[2]
            line = PeerLine(
                baud=_speeds().get(attrs[5]),
                stop_bits=2 if cflag & termios.CSTOPB else 1,
                odd=bool(cflag & termios.PARENB or cflag & termios.PARODD),
            )
            _park(slave)
        except termios.error:
            return  # the pty is going away: its close is reported elsewhere
        self.note_line(line)

    def receive(self) -> bytes:
        """What the peer has written since the last call; b"" if nothing."""
        self._check_open("receive")
        self.flush()
        self._look_at_line()  # the settings it wrote them with come first
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
