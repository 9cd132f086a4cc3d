"""Logging into the message stack, periodic overall state, and the words the PLC reads.

Messages enter the stack only while logging is possible (time set, configuration
accepted, no global stop: DEM 2.5-1, 3.4-3, 4.2-3); channels 0..23 only when
selected in OWxy,2/3 (3.2-2).  The periodic overall-state message (3.2-1 PER) is
timed by the module's own clock, the only clock the module has: it is due every PER
minutes of module time from the time setting, so its time-stamps fall on whole
minutes of module time even when that clock drifts or runs free in a
synchronization fault (2.5-6).
"""

from __future__ import annotations

from typing import Any

from fieldtwin.clock import Handle
from fieldtwin.tsx.dem24.civil import CivilTime
from fieldtwin.tsx.dem24.config import FB_STACK_FULL, FB_SUPPLY, Dem24Config
from fieldtwin.tsx.dem24.inputs import CHANNELS, InputBank
from fieldtwin.tsx.dem24.oscillation import Detector
from fieldtwin.tsx.dem24.stack import (
    NEARLY_FULL,
    Message,
    MessageStack,
    MessageType,
    change_body,
    overall_body,
)
from fieldtwin.tsx.dem24.timebase import Timebase
from fieldtwin.tsx.module import IntelligentModule, ModuleState
from fieldtwin.words import get_bit

# Discrete input bits Ixy,i (DEM 2.4-2 reconstructed, AMB-DEM-01)
I_READY, I_NOT_EMPTY, I_NEARLY_FULL, I_SATURATED, I_SYNC_FAULT, I_PULSE = 0, 1, 2, 3, 4, 7

# OWxy,1 command bits (DEM 2.4-3, 4.2-1, AMB-DEM-03)
OW1_STOP, OW1_PURGE, OW1_OVERALL = 0, 1, 2

MINUTE_MS = 60_000


class Logbook(IntelligentModule):
    """The logging side of :class:`fieldtwin.tsx.dem24.module.Dem24Core`."""

    config: Dem24Config
    default_config: bool
    diag_word: int
    timebase: Timebase
    stack: MessageStack
    inputs: InputBank
    detectors: list[Detector] | None
    terminal_block: bool
    supply: bool
    pulse_image: bool
    _periodic: Handle | None
    _periodic_due_ms: int | None

    # --- what may be logged ------------------------------------------------------

    @property
    def logging(self) -> bool:
        """Messages enter the stack (DEM 2.5-1, 3.4-3, 4.2-3 global stop)."""
        return (
            self.timebase.ready
            and not self.awaiting_configuration
            and not get_bit(self.ow[1], OW1_STOP)
        )

    def selected(self) -> int:
        """Channels to time-stamp: OWxy,2 (0..15) and OWxy,3 bits 0..7 (DEM 3.2-2)."""
        return self.ow[2] | ((self.ow[3] & 0xFF) << 16)

    def _stamp(self, t: int) -> int | None:
        return self.timebase.clock.ms(t) if self.timebase.ready else None

    def _log(self, message_type: MessageType, stamp: int | None, body: Any) -> None:
        if stamp is None or not self.logging or self.state is not ModuleState.OPERATIONAL:
            return
        message = Message(
            message_type,
            CivilTime.from_ms(stamp),
            self.timebase.fault,
            self.timebase.indicator,
            self.rack,
            self.slot,
            body,
        )
        self.stack.push(message)  # DEM 2.3-4: lost when full, flagged in the next one
        self.set_fault(FB_STACK_FULL, self.stack.full)

    def _log_change(self, channel: int, state: int, stamp: int | None) -> None:
        if channel < CHANNELS and not (self.selected() >> channel) & 1:
            return  # DEM 3.2-2: channels not selected behave like discrete inputs
        self._log(MessageType.CHANGE, stamp, change_body(channel, state))

    def log_overall(self, now: int) -> None:
        """A type 1 message: selection, oscillating channels, states, faults (DEM 4.2-2)."""
        oscillating = 0
        if self.detectors is not None:
            oscillating = sum(int(d.oscillating) << i for i, d in enumerate(self.detectors))
        faults = (
            self.timebase.fault,
            not self.terminal_block,
            self.fault_active(FB_SUPPLY),
        )
        body = overall_body(self.selected(), oscillating, self.image(), faults)
        self._log(MessageType.OVERALL, self._stamp(now), body)
        self._refresh_words()

    def read_messages(self, count: int) -> list[Message]:
        """Remove and return up to ``count`` messages, oldest first (DEM 4.2-3)."""
        messages = self.stack.pop(count)
        self.set_fault(FB_STACK_FULL, self.stack.full)
        self._refresh_words()
        return messages

    # --- periodic logging on the module clock (DEM 3.2-1 PER) ------------------------

    def _start_periodic(self, now: int) -> None:
        """PER minutes of module time from now (the time setting, a new configuration)."""
        self._periodic_due_ms = None
        if self.config.periodic and self.timebase.ready and self.state is not ModuleState.OFF:
            self._periodic_due_ms = self.timebase.clock.ms(now) + self.config.per_min * MINUTE_MS
        self._arm_periodic(now)

    def _arm_periodic(self, now: int) -> None:
        """(Re)compute when the module clock reaches the due time: after a pulse resets
        the clock or its drift changes, the same module time falls at another instant."""
        if self._periodic is not None:
            self._periodic.cancel()
            self._periodic = None
        if self._periodic_due_ms is not None:
            at = self.timebase.clock.when(self._periodic_due_ms, now)
            self._periodic = self.call_at(at, self._periodic_log)

    def _periodic_log(self, now: int) -> None:
        self._periodic = None
        self.log_overall(now)  # DEM 3.2-1 PER: overall state every PER minutes
        if self._periodic_due_ms is not None:
            self._periodic_due_ms += self.config.per_min * MINUTE_MS
        self._arm_periodic(now)

    # --- words and bits ------------------------------------------------------------

    def image(self) -> int:
        """IWxy,6/7: the inputs, or their fallback while unreadable (DEM 3.2-1 DEF)."""
        if self._readable() or self.config.maintain:
            return self.inputs.levels()
        return 0

    def _readable(self) -> bool:
        """Inputs read: terminal block fitted, monitored supply present (DEM 2.5-6)."""
        return self.terminal_block and (self.supply or not self.config.supply_monitoring)

    def _refresh_words(self) -> None:
        if self.state is ModuleState.OFF:
            return
        ready = self.timebase.ready
        count = len(self.stack)
        iw2 = self.diag_word
        iw2 |= int(not self.logging) << 0  # DEM 2.4-3 IWxy,2,0: 1 = no logging
        iw2 |= int(ready) << 7
        iw2 |= int(self.fault_active(FB_SUPPLY)) << 8
        iw2 |= int(self.default_config) << 0xD
        image = self.image()
        self.iw[2], self.iw[5] = iw2, count
        self.iw[6], self.iw[7] = image & 0xFFFF, image >> 16
        self.i_bits = (
            (int(ready) << I_READY)
            | (int(count > 0) << I_NOT_EMPTY)
            | (int(count >= NEARLY_FULL) << I_NEARLY_FULL)
            | (int(self.stack.full) << I_SATURATED)
            | (int(self.timebase.fault) << I_SYNC_FAULT)
            | (int(self.pulse_image) << I_PULSE)
        )
