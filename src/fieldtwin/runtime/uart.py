"""What the device's UART makes of a master on a pty (issue 23 item 1).

A pty carries no bits, but its termios settings are the master's: the speed and
stop bits it set, and odd parity (fieldtwin.transports.pty.PeerLine; a Linux pty
shows neither even parity nor the character size).  A real UART at the device's
own settings reads a master at another speed or parity as framing and parity
errors and wrong characters: the frame never passes, there is no answer.  So,
while the master's settings differ from the device's (``strict``, the default),
every byte the master sends is rejected: counted as a wrong character by every
slave of the line (TES 6.2.3.2 01Bh, "received wrong characters"), published with
the reason, and not framed.  ``strict = False`` (the plant key ``strict_line``)
reads every master as if it were set right, as before issue 23.

On a serial port the port's own UART does this itself; nothing here is needed.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from fieldtwin.charformat import CharFormat
from fieldtwin.modbus.model import Counter
from fieldtwin.modbus.slave import SlaveSet
from fieldtwin.transports.pty import PeerLine

REASON_SETTINGS = "line_settings"


class PeerLineSource(Protocol):
    def peer_line(self) -> PeerLine | None: ...


class Uart:
    """The device's receiver on one pty line: ``admit`` each chunk before the framer."""

    def __init__(
        self,
        source: PeerLineSource,
        own: CharFormat,
        slaves: SlaveSet,
        what: str = "TES",
        strict: bool = True,
        report: Callable[[str], None] | None = None,
    ) -> None:
        self.source = source
        self.own = own
        self.slaves = slaves
        self.what = what
        self.strict = strict
        self.report = report
        self.master: PeerLine | None = None  # the master's settings as last seen
        self.rejected = 0  # bytes rejected for the line settings
        self._told: PeerLine | None = None

    @property
    def differs(self) -> bool:
        return self.master is not None and self.master.differs(self.own)

    def describe(self) -> str:
        """``line settings differ: master 9600 8N1, TES 38400 8E1`` (or ``agree``)."""
        master = self.master
        if master is None:
            return f"line settings: master not seen, {self.what} {self.own}"
        seen = master.seen_as(self.own)
        shown = str(seen) if seen is not None else f"(a rate termios cannot name) {master}"
        verb = "differ" if self.differs else "agree"
        return f"line settings {verb}: master {shown}, {self.what} {self.own}"

    def look(self) -> None:
        """Read the master's settings if it changed them (and park the pty again)."""
        seen = self.source.peer_line()
        if seen is not None:
            self.master = seen
        if self.master is not None and self.master != self._told:
            self._told = self.master
            if self.report is not None and (self.differs or self.rejected):
                ignored = "" if self.strict else " (strict_line = false: read as if set right)"
                self.report(self.describe() + ignored)

    def admit(self, data: bytes, now: int) -> bytes | None:
        """``data`` as the device's UART delivers it; None: rejected (counted)."""
        self.look()
        if not self.strict or not self.differs:
            return data
        # TES 6.2.3.2 01Bh: characters a UART at the wrong speed or parity cannot read
        self.rejected += len(data)
        self.slaves.count_all(Counter.WRONG_CHARACTERS, now, len(data))
        return None
