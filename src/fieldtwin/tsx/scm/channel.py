"""What the half-duplex and full-duplex channels share (SCM 3.2, 5.1, 6.3).

A channel owns its configuration, the UART (:class:`Line`) and the adaptor
signals; it filters what the receiver delivers (CD inhibition, parity and
format errors, XON/XOFF on transmission) before its mode handles it, and
builds what a transmission request sends (end-of-transmission characters,
auto-LF).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from typing import Protocol

from fieldtwin.clock import Handle
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.config import ChannelConfig
from fieldtwin.tsx.scm.line import ECHO_BACKLOG, Line, RxChar
from fieldtwin.tsx.scm.requests import Job
from fieldtwin.tsx.textblock import V_ERROR, Answer, Exchange

XON, XOFF, BS, SP, CR, LF = 0x11, 0x13, 0x08, 0x20, 0x0D, 0x0A


class AppFault(enum.Enum):
    """Application faults of the 3rd word of the fault bit string (SCM 6.3)."""

    WRONG_ECHO = "incorrect echo after 3 tries"
    NO_ECHO = "no echo after 3 tries"
    READ_TIMEOUT = "time-out on READ request"
    WRITE_TIMEOUT = "time-out on WRITE request"
    WR_TIMEOUT = "time-out on WRITE/READ request"
    PARITY = "reception parity fault"
    FORMAT = "format fault in reception"
    OVERLOAD = "overload fault in reception"


class Host(Protocol):
    """What a channel needs from its module."""

    def call_at(self, at: int, callback: Callable[[int], None]) -> Handle: ...

    def app_fault(self, channel: int, fault: AppFault) -> None: ...

    def changed(self) -> None: ...


class Channel:
    """Base of a configured (or not yet configured) channel."""

    def __init__(
        self,
        host: Host,
        index: int,
        line: Line,
        signals: Signals,
        config: ChannelConfig | None,
    ) -> None:
        self.host = host
        self.index = index
        self.line = line
        self.signals = signals
        self.config = config
        self.xoff_held = False  # SCM 3.2 Xon-Xoff (T): XOFF received, transmission paused
        line.on_char = self._on_line_char
        line.on_sent = self.on_sent
        line.tx_allowed = self.tx_allowed
        line.on_overrun = self._on_overrun
        if config is not None:
            line.fmt = config.fmt
        line.half_speed = signals.half_speed
        line.invert_rx = signals.rx_inverted

    # --- what the module asks --------------------------------------------

    @property
    def configured(self) -> bool:
        return self.config is not None

    @property
    def busy(self) -> bool:
        return self.receiving or self.transmitting

    @property
    def receiving(self) -> bool:
        return False

    @property
    def transmitting(self) -> bool:
        return False

    def request(self, exchange: Exchange, job: Job, now: int) -> None:
        """An unconfigured channel cannot operate (SCM 3.1): report H'FD'."""
        exchange.complete(Answer(v=V_ERROR), now)

    def abort(self, now: int, write: bool = True, read: bool = True) -> list[Exchange]:
        """Stop the request(s) in progress; returns the exchanges to cancel."""
        return []

    def power_off(self) -> None:
        self.line.reset()

    def start(self, now: int) -> None:
        """Configuration accepted or power returned: the channel is ready."""

    def message_reset(self, now: int) -> None:
        """OWxy,0,2: the message system is reset."""

    def describe(self) -> str:
        return "not configured"

    # --- the transmitter --------------------------------------------------

    def tx_allowed(self) -> bool:
        return self.signals.transmit_enabled and not self.xoff_held

    def on_sent(self, value: int, tag: str, now: int) -> None:
        """A character has left the transmitter."""

    def signals_changed(self, now: int) -> None:
        self.line.half_speed = self.signals.half_speed
        self.line.invert_rx = self.signals.rx_inverted
        self.line.kick(now)

    def outgoing(self, chars: bytes) -> tuple[bytes, int]:
        """Characters a transmission sends and its report (SCM 3.2 ETC, auto-LF; AMB-SCM-11)."""
        assert self.config is not None
        out = bytearray()
        report = 0
        for value in chars:
            which = self.config.etc.match(value)
            if which:
                if self.config.etc.included(which):
                    out.append(value)
                report = which
                break
            out.append(value)
        return self.with_auto_lf(bytes(out)), report

    def with_auto_lf(self, chars: bytes) -> bytes:
        # SCM 3.2 Auto-LF: a CR sent is followed by an LF
        if self.config is None or not self.config.auto_lf:
            return chars
        return chars.replace(bytes([CR]), bytes([CR, LF]))

    # --- the receiver -----------------------------------------------------

    def _on_line_char(self, char: RxChar, now: int) -> None:
        if not self.signals.receive_enabled or self.config is None:
            return  # SCM 5.1: CD at 1 inhibits the reception circuit
        if char.parity_error or self.line.inject_parity:
            self.host.app_fault(self.index, AppFault.PARITY)
        if char.format_error or self.line.inject_format:
            self.host.app_fault(self.index, AppFault.FORMAT)
        value = char.value
        if self.config.xon_xoff_tx and value in (XON, XOFF):
            self.xoff_held = value == XOFF  # SCM 3.2 Xon-Xoff (T)
            self.line.kick(now)
            self.host.changed()
            return
        self.on_char(value, now)
        self.host.changed()

    def on_char(self, value: int, now: int) -> None:
        """A character received (after flow control) while configured."""

    def _on_overrun(self, lost: int, now: int) -> None:
        if not self.signals.receive_enabled or self.config is None:
            return  # nothing was being received: nothing to report
        self.overrun(now)
        self.host.changed()

    def overrun(self, now: int) -> None:
        """Characters came faster than the line carries them and were lost (SCM 6.3).

        A half-duplex channel has no fault bit for it (the 3rd word of the fault bit
        string of the 20 names none): the characters are only lost.
        """

    def echo(self, chars: bytes, now: int, tag: str = "") -> None:
        """Send a reception echo (SCM 3.2), bounded: an echo that cannot keep up is cut."""
        self.line.send(chars, now, tag=tag, limit=ECHO_BACKLOG)
