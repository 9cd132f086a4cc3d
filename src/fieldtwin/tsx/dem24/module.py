"""The TSX DEM 2412 / 2413 time-stamping module (the manual tsx-dem-24-time-stamping.txt).

Sans-IO and event-driven: the module acts at input edges (from the signals' next
change), at the ends of the input filters, at synchronization pulses, at the
pulse-loss deadline, at oscillation checks and at periodic logging; nothing runs per
PLC scan.  The module is composed of its parts, each declared here and owning its own
state: the input bank (:mod:`.inputs`), the logbook (stack + time base,
:mod:`.logbook`), the synchronization input (:mod:`.syncinput`) and, when the
configuration asks for it, the oscillation monitor (:mod:`.oscillation`).  The Text
Block requests live in :mod:`.requests`, the two models in :mod:`.models`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

from fieldtwin.clock import Handle
from fieldtwin.errors import ConfigError
from fieldtwin.signals import DiscreteSignal
from fieldtwin.tsx.dem24 import requests
from fieldtwin.tsx.dem24.config import (
    DEFAULT_CONFIG,
    FB_CONFIG_REFUSED,
    FB_STACK_FULL,
    FB_SUPPLY,
    FB_SYNC,
    FB_TERMINAL,
    Dem24Config,
)
from fieldtwin.tsx.dem24.inputs import (
    CHANNELS,
    TYPE1_24V,
    UNSTAMPED,
    InputBank,
    InputSignal,
    Thresholds,
    check_channel,
)
from fieldtwin.tsx.dem24.logbook import Logbook
from fieldtwin.tsx.dem24.oscillation import Detector, Monitor
from fieldtwin.tsx.dem24.oscillation import Thresholds as OscThresholds
from fieldtwin.tsx.dem24.registers import (
    I_NEARLY_FULL,
    I_NOT_EMPTY,
    I_PULSE,
    I_READY,
    I_SATURATED,
    I_SYNC_FAULT,
    OW1_OVERALL,
    OW1_PURGE,
    OW1_STOP,
    input_bits,
    status_word,
)
from fieldtwin.tsx.dem24.stack import (
    CH_SUPPLY,
    CH_SYNC,
    CH_TERMINAL,
    NEARLY_FULL,
    Body,
    Message,
    MessageStack,
    MessageType,
    change_body,
    overall_body,
)
from fieldtwin.tsx.dem24.sync import SYNC_OUTPUT_MAX, PulseSource
from fieldtwin.tsx.dem24.syncinput import SYNC_PULSE_US, SyncInput, check_width
from fieldtwin.tsx.dem24.timebase import SyncOutcome, Timebase
from fieldtwin.tsx.module import FaultCategory, IntelligentModule, ModuleContext, ModuleState
from fieldtwin.tsx.textblock import Exchange
from fieldtwin.words import get_bit

_CHANGE = MessageType.CHANGE


class Dem24(IntelligentModule):
    """What the DEM 2412 and 2413 share; the models set thresholds and codes."""

    type_name: ClassVar[str] = "TSX DEM 24"
    thresholds: ClassVar[Thresholds] = TYPE1_24V
    fault_string_bytes = 12  # DEM 4.3: 96 bits
    terminal_block_fault_bit = FB_TERMINAL
    plc_limit = ("time-stamping modules", 32)  # DEM 6.2-2 note: 32 in one PLC configuration
    # The shortcuts of the per-edge and per-message path: after an accepted edge only
    # what an edge changes is written (_refresh_edge), the stack-full fault is set
    # only when it changes (_stack_fault), an oscillating input's check is armed
    # inline (Monitor.inline).  False (the reference of the tests, issue 15): every
    # word and bit recomputed (_refresh_words), set_fault at every message,
    # Detector.transition and Monitor._arm at every edge.
    shortcuts = True
    # Issue 25, on top of ``shortcuts``: an oscillating input's check stays armed at
    # an edge and moves itself where the reference re-arms it (Monitor.kept), and a
    # filter's confirmation runs inline at the edge's event when nothing comes between
    # (InputBank.folded).  Every event keeps its instant and its order; False (with
    # ``inputs.folded`` False) is the reference of tests/tsx/dem24/test_kept_checks.py.
    kept_checks = True

    def __init__(
        self,
        ctx: ModuleContext,
        rack: int,
        slot: int,
        *,
        declared_code: int | None = None,
        clock_drift_ppm: float = 0.0,
    ) -> None:
        super().__init__(ctx, rack, slot, declared_code=declared_code)
        self.clock_drift_ppm = float(clock_drift_ppm)
        self.config: Dem24Config = DEFAULT_CONFIG
        self.default_config = True
        self.diag_word = 0
        self.logbook = Logbook(
            rack, slot, self.clock_drift_ppm, self.call_at, self.log_overall, self._pulse_lost
        )
        self.inputs = InputBank(self.clock, self.thresholds, self.logbook.stamp, self._accepted)
        self.logbook.before_change = self.inputs.settle_stamps
        self.sync_input = SyncInput(self.clock, self.thresholds, self._take_pulse, self._repeat)
        self.oscillation: Monitor | None = None  # with OSC in the configuration (3.2-1)
        self.pulse_image = False
        self.terminal_block = True  # fitted
        self.supply = True  # external supply present
        self.sync_outputs: list[Dem24] = []
        self.pulse_source: PulseSource | None = None
        self.plant_startup: list[Any] = []  # requests the plant file applies after self-test
        self.edges_stamped = 0
        self._words_fresh = False  # written by _refresh_words since the last supply fault

    # --- the parts, for inspection ----------------------------------------------------

    @property
    def timebase(self) -> Timebase:
        return self.logbook.timebase

    @property
    def stack(self) -> MessageStack:
        return self.logbook.stack

    @property
    def detectors(self) -> list[Detector] | None:
        return None if self.oscillation is None else self.oscillation.detectors

    # --- public API: inputs and pulses ------------------------------------------------

    def set_input(self, channel: int, value: bool | float) -> None:
        """A bool, or volts judged as IEC 61131-2 type 1 (DEM 6.1)."""
        self.inputs.set_value(check_channel(channel), value, self.clock.now)

    def set_signal(self, channel: int, signal: InputSignal | None) -> None:
        """Drive an input from a signal (bools, or volts switched where they cross a limit)."""
        self.inputs.attach(check_channel(channel), signal)

    def sync_pulse(self, width_us: int = SYNC_PULSE_US) -> None:
        """One synchronization pulse on IN-SYN now, ``width_us`` long (DEM 7.2)."""
        self.receive_pulse(self.clock.now, width_us)

    def receive_pulse(self, now: int, width_us: int = SYNC_PULSE_US) -> None:
        """A pulse on IN-SYN from ``now``: counted when it lasts the 500 us filter (1.2-1)."""
        self.sync_input.pulse(now, width_us)

    def set_sync_input(self, value: bool | float) -> None:
        """The IN-SYN level now: a bool, or volts of either sign (DEM 7.2)."""
        self.sync_input.set_level(value, self.clock.now)

    def set_sync_signal(self, signal: DiscreteSignal | None) -> None:
        """Drive IN-SYN from a discrete signal (e.g. a ``PulseTrain``); None: stop."""
        self.sync_input.attach(signal)

    def connect_sync_output(self, other: Dem24) -> None:
        """Wire OUT-SYN to another module's IN-SYN (at most 32, DEM 7.2)."""
        if len(self.sync_outputs) >= SYNC_OUTPUT_MAX:
            raise ConfigError(
                f"sync output of slot {self.address} already drives {SYNC_OUTPUT_MAX} modules"
                " (allowed at most 32)"
            )
        if other is self or other in self.sync_outputs:
            raise ConfigError(f"slot {other.address} cannot be wired twice or to itself")
        self.sync_outputs.append(other)

    def attach_pulse_source(
        self, period_us: int, start_us: int = 0, width_us: int = SYNC_PULSE_US
    ) -> PulseSource:
        """An external pulse generator on IN-SYN (replaces any previous one)."""
        check_width(width_us)
        if self.pulse_source is not None:
            self.pulse_source.stop()
        pulse = self.sync_input.pulse
        self.pulse_source = PulseSource(
            self.clock, period_us, start_us, lambda now: pulse(now, width_us)
        )
        return self.pulse_source

    def set_clock_drift(self, ppm: float) -> None:
        """Make the module clock fast (> 0) or slow by ``ppm`` (DEM 7.2: within 25 ppm)."""
        self.clock_drift_ppm = float(ppm)
        self.logbook.set_drift(self.clock_drift_ppm, self.clock.now)

    def set_terminal_block(self, fitted: bool) -> None:
        """Fit or remove the TSX BLK4 terminal block (DEM 4.3, 7.2 monitoring)."""
        if fitted != self.terminal_block:
            self.terminal_block = fitted
            self._fault_input(FB_TERMINAL, CH_TERMINAL, not fitted)

    def set_supply(self, present: bool) -> None:
        """External 24/48 V supply of the inputs (DEM 3.2-1 AI EXT)."""
        if present != self.supply:
            self.supply = present
            self.inputs.supply(present, self.clock.now)
            if self.config.supply_monitoring:
                self._fault_input(FB_SUPPLY, CH_SUPPLY, not present)

    # --- the operating modes (base hooks) -------------------------------------------

    def on_power_on(self, now: int) -> None:
        # DEM 2.5-3: no protected memory, configuration and time are lost
        self.config, self.default_config, self.diag_word = DEFAULT_CONFIG, True, 0
        self.logbook.reset(self.clock_drift_ppm)
        self._stop_oscillation()
        self.pulse_image = False
        self.inputs.stop()
        self.inputs.reset_levels()
        self.inputs.set_filter_ms(0)

    def on_self_test_done(self, now: int) -> None:
        if not self.terminal_block:
            self.set_fault(FB_TERMINAL, True)
        self._update_reading(now, silent=True)
        for action in self.plant_startup:
            action(self, now)
        self._refresh_words()

    def on_power_off(self, now: int) -> None:
        self.inputs.stop()

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        old, new = old_ow[1], self.ow[1]
        if get_bit(new, OW1_PURGE) and not get_bit(old, OW1_PURGE):
            self.stack.purge()  # DEM 4.2-1 rising edge: purge the stack
        if get_bit(new, OW1_OVERALL) and not get_bit(old, OW1_OVERALL):
            self.log_overall(now)  # DEM 4.2-3 rising edge: log the overall state
        self._refresh_words()

    def set_fault(self, bit: int, active: bool, category: FaultCategory | None = None) -> None:
        super().set_fault(bit, active, category)
        if bit == FB_SUPPLY:  # IWxy,2,8: not written before the next _refresh_words
            self._words_fresh = False

    def fault_category_of(self, bit: int) -> FaultCategory:
        if bit < 16:
            return FaultCategory.BLOCKING
        if bit in (FB_TERMINAL, FB_SUPPLY):
            return FaultCategory.MODULE  # DEM 4.3 module/processor faults
        return FaultCategory.APPLICATION

    def handle_request(self, exchange: Exchange, now: int) -> None:
        requests.handle(self, exchange, now)

    # --- configuration ---------------------------------------------------------------

    def apply_config(self, config: Dem24Config, now: int) -> None:
        """A configuration accepted (DEM 3.4-3), or the default."""
        self.config, self.default_config = config, False
        self.diag_word = 0
        self.awaiting_configuration = False
        self.set_fault(FB_CONFIG_REFUSED, False)
        per_min = config.per_min if config.periodic else 0
        self.logbook.configure(config.t_syn_s, config.drift_ms, per_min)
        self.inputs.set_filter_ms(config.filt_ms)
        self._stop_oscillation()
        if config.oscillation:
            th = OscThresholds.from_config(
                config.t_max_s, config.n_max, config.t_min_s, config.n_min
            )
            kept = self.shortcuts and self.kept_checks
            self.oscillation = Monitor(
                th,
                CHANNELS,
                self._check_at,
                self._normal_again,
                inline=self.shortcuts,
                kept=(self.clock.reserve, self._check_as) if kept else None,
            )
        monitored = config.supply_monitoring and not self.supply
        if monitored != self.fault_active(FB_SUPPLY):
            self._fault_input(FB_SUPPLY, CH_SUPPLY, monitored)
        self.logbook.start_periodic(now)
        self.refresh_status()
        self._refresh_words()

    def _check_at(self, at: int, callback: Callable[[int], None]) -> Handle:
        """An oscillation check at ``at``, or now if that is past: with N-MIN above the
        changes that made an input oscillating, it is normal again at once (the check
        is due 1 us after the edge, the declaration comes at its confirmation)."""
        now = self.clock.now
        return self.call_at(at if at >= now else now, callback)

    def _check_as(self, at: int, seq: int, callback: Callable[[int], None]) -> Handle:
        """A kept oscillation check at ``at`` with the sequence number ``seq`` (reserved
        when the reference scheduled it); a power-off cancels it like ``call_at``'s."""
        return self.call_at_as(at, seq, callback)

    def refuse_config(self, diag_word: int) -> None:
        """DEM 3.4-3: awaiting configuration, diagnostic bits, time-stamping stops."""
        self.awaiting_configuration = True
        self.diag_word = diag_word
        self.set_fault(FB_CONFIG_REFUSED, True)
        self._refresh_words()

    def set_pulses_lost(self, lost: bool) -> None:
        """The synchronization pulses no longer reach IN-SYN (or reach it again)."""
        if self.pulse_source is None:
            raise ConfigError("fault 'pulses': this module has no pulse source (sync key)")
        self.pulse_source.silenced = lost

    # --- time -----------------------------------------------------------------------

    def _repeat(self, active: bool, now: int) -> None:
        """OUT-SYN: "an amplification of the synchronization input" (DEM 1.2-1)."""
        if self.state is ModuleState.OFF:
            return
        for other in self.sync_outputs:
            other.sync_input.set_level(active, now)

    def _take_pulse(self, edge: int) -> None:
        """A pulse past the filter: taken by the time base at its leading edge (4.1-3)."""
        if self.state is not ModuleState.OPERATIONAL:
            return
        now = self.clock.now
        self.pulse_image = not self.pulse_image  # DEM 2.4-2 note: Ixy,7 changes at each pulse
        self._sync_outcome(self.logbook.pulse(edge, now), now)

    def _pulse_lost(self, now: int) -> None:
        self._sync_outcome(self.timebase.pulse_lost(now), now)

    def _sync_outcome(self, outcome: SyncOutcome, now: int) -> None:
        if outcome.fault is not None:
            self.set_fault(FB_SYNC, outcome.fault)  # DEM 4.3: application fault, ERR LED
            self._log_change(CH_SYNC, int(outcome.fault), self.logbook.stamp(now))
        if outcome.time_set:
            self.log_overall(now)  # DEM 4.2-3: first message after the time is set
        self._refresh_words()

    # --- inputs -------------------------------------------------------------------------

    def _accepted(self, channel: int, level: bool, edge: int, stamp: int | None, now: int) -> None:
        self.edges_stamped += 1
        state = 1 if level else 0
        oscillation = self.oscillation
        if oscillation is not None:
            state = oscillation.judge(channel, edge, state, now)  # DEM 2.3-3
        if stamp == UNSTAMPED and state >= 0:  # to be logged: the clock's reading at the edge
            stamp = self.logbook.stamp(edge)
        if not self.shortcuts:
            if state >= 0:
                self._log_change(channel, state, stamp)
            self._refresh_words()
        elif state >= 0:
            self._log_edge(channel, state, stamp)
        elif self._mode.state is ModuleState.OPERATIONAL and self._words_fresh:
            # nothing logged: _refresh_edge(False) inlined, the levels IWxy,6/7 only
            config = self.config
            readable = self.terminal_block and (self.supply or not config.supply_monitoring)
            image = self.inputs.level_bits if readable or config.maintain else 0
            iw = self._iw
            low, high = image & 0xFFFF, image >> 16
            if iw[6] != low or iw[7] != high:
                iw[6:8] = low, high
        else:
            self._refresh_words()  # as _refresh_edge(False) does there

    def _log_edge(self, channel: int, state: int, stamp: int | None) -> None:
        """``_log_change(channel, state, stamp)`` then ``_refresh_edge(True)``, fused (the
        shortcut of an accepted edge): the same conditions (``_log``'s, the channel's
        selection), the same message, the stack-full fault set only when it changes
        (``_stack_fault``, operational known)."""
        ow = self.ow
        logbook = self.logbook
        if (
            stamp is not None
            and ((ow[2] | ((ow[3] & 0xFF) << 16)) >> channel) & 1  # self.selected()
            and not (ow[1] >> OW1_STOP) & 1  # self.logging: no global stop,
            and not self.awaiting_configuration  # configured,
            and logbook.timebase.ready  # the time set
            and self._mode.state is ModuleState.OPERATIONAL
        ):
            full = logbook.push(_CHANGE, stamp, ((channel << 8) | state, 0, 0, 0, 0, 0))
            if full != self._faults.active(FB_STACK_FULL):
                self.set_fault(FB_STACK_FULL, full)
        self._refresh_edge(True)

    def _normal_again(self, channel: int, now: int) -> None:
        """An oscillating input is normal again: its state (AMB-DEM-11)."""
        self._log_change(channel, int(self.inputs.level(channel)), self.logbook.stamp(now))
        self._refresh_words()

    def _stop_oscillation(self) -> None:
        if self.oscillation is not None:
            self.oscillation.stop()
        self.oscillation = None

    def _update_reading(self, now: int, *, silent: bool = False) -> None:
        if self.state is not ModuleState.OPERATIONAL:
            return
        if self._readable() and not self.inputs.active:
            self.inputs.start(now, silent=silent)
        elif not self._readable() and self.inputs.active:
            self.inputs.stop()

    def _fault_input(self, bit: int, channel: int, active: bool) -> None:
        now = self.clock.now
        if self.state is ModuleState.OFF:
            return
        if self.state is ModuleState.OPERATIONAL:
            self.set_fault(bit, active)
            self._log_change(channel, int(active), self.logbook.stamp(now))  # AMB-DEM-19
        self._update_reading(now)
        self._refresh_words()

    # --- logging ------------------------------------------------------------------------

    @property
    def logging(self) -> bool:
        """Messages enter the stack (DEM 2.5-1, 3.4-3, 4.2-3 global stop)."""
        return (
            self.logbook.timebase.ready
            and not self.awaiting_configuration
            and not get_bit(self.ow[1], OW1_STOP)
        )

    def selected(self) -> int:
        """Channels to time-stamp: OWxy,2 (0..15) and OWxy,3 bits 0..7 (DEM 3.2-2)."""
        return self.ow[2] | ((self.ow[3] & 0xFF) << 16)

    def _log(self, message_type: MessageType, stamp: int | None, body: Body) -> None:
        if stamp is None or not self.logging or self.state is not ModuleState.OPERATIONAL:
            return
        self._stack_fault(self.logbook.push(message_type, stamp, body))

    def _stack_fault(self, full: bool) -> None:
        """``set_fault(FB_STACK_FULL, full)`` (DEM 4.3), at every message logged or read.

        With ``shortcuts``, skipped while operational and the fault already is
        ``full``: the latch then stays as it is and IWxy,0, refreshed after every change
        of what it shows, reads the same (set_fault would recompute it, and mark the
        bus face changed)."""
        if (
            self.shortcuts
            and full == self.fault_active(FB_STACK_FULL)
            and self._mode.state is ModuleState.OPERATIONAL
        ):
            return
        self.set_fault(FB_STACK_FULL, full)

    def _log_change(self, channel: int, state: int, stamp: int | None) -> None:
        if channel < CHANNELS and not (self.selected() >> channel) & 1:
            return  # DEM 3.2-2: channels not selected behave like discrete inputs
        self._log(MessageType.CHANGE, stamp, change_body(channel, state))

    def log_overall(self, now: int) -> None:
        """A type 1 message: selection, oscillating channels, states, faults (DEM 4.2-2)."""
        oscillating = 0 if self.oscillation is None else self.oscillation.oscillating()
        faults = (
            self.timebase.fault,
            not self.terminal_block,
            self.fault_active(FB_SUPPLY),
        )
        body = overall_body(self.selected(), oscillating, self.image(), faults)
        self._log(MessageType.OVERALL, self.logbook.stamp(now), body)
        self._refresh_words()

    def read_messages(self, count: int) -> list[Message]:
        """Remove and return up to ``count`` messages, oldest first (DEM 4.2-3)."""
        messages = self.logbook.read(count)
        self._stack_fault(self.stack.full)
        if self.shortcuts:
            self._refresh_edge(True)  # a read changes the stack count only
        else:
            self._refresh_words()
        return messages

    # --- words and bits ------------------------------------------------------------

    def image(self) -> int:
        """IWxy,6/7: the inputs, or their fallback while unreadable (DEM 3.2-1 DEF)."""
        if self._readable() or self.config.maintain:
            return self.inputs.levels()
        return 0

    def _readable(self) -> bool:
        """Inputs read: terminal block fitted, monitored supply present (DEM 2.5-6)."""
        return self.terminal_block and (self.supply or not self.config.supply_monitoring)

    def _refresh_edge(self, logged: bool) -> None:
        """``_refresh_words`` after an accepted edge or a read of messages: what they can
        change, written as ``_refresh_words`` writes it.  An edge changes the levels
        (IWxy,6/7) and, when ``logged``, the stack count (IWxy,5) and with it the stack
        bits of Ixy,0..7, as a read does; IWxy,2 depends on nothing they change
        (configuration, global stop, time base, supply fault), and every change of
        those refreshes all the words.  Operational only: during the self-test the
        words read 0 until it ends (a read of messages then writes them all); and not
        after a supply fault set from outside (``set_fault``, ``hardware_fault``), which
        IWxy,2 shows from the next refresh of every word."""
        if self._mode.state is not ModuleState.OPERATIONAL or not self._words_fresh:
            self._refresh_words()
            return
        iw = self._iw
        # self.image(), inlined
        config = self.config
        readable = self.terminal_block and (self.supply or not config.supply_monitoring)
        image = self.inputs.level_bits if readable or config.maintain else 0
        low, high = image & 0xFFFF, image >> 16
        if not logged:  # the same words as iw[5:8] = count, low, high (count as it was)
            if iw[6] != low:
                iw[6] = low
            if iw[7] != high:
                iw[7] = high
            return
        stack = self.logbook.stack
        count = len(stack)
        if iw[5] != count:
            iw[5:8] = count, low, high
            timebase = self.logbook.timebase
            # input_bits(timebase.ready, count, stack.full, timebase.fault, pulse_image)
            self.i_bits = (
                (timebase.ready << I_READY)
                | ((count > 0) << I_NOT_EMPTY)
                | ((count >= NEARLY_FULL) << I_NEARLY_FULL)
                | ((count >= stack.size) << I_SATURATED)
                | (timebase.fault << I_SYNC_FAULT)
                | (self.pulse_image << I_PULSE)
            )
        elif iw[6] != low or iw[7] != high:
            iw[5:8] = count, low, high

    def _refresh_words(self) -> None:
        if self._mode.state is ModuleState.OFF:
            return
        self._words_fresh = True
        logbook = self.logbook
        timebase, stack = logbook.timebase, logbook.stack
        ready, count = timebase.ready, len(stack)
        supply = self.fault_active(FB_SUPPLY)
        image = self.image()
        iw = self.iw
        # self.logging, with ``ready`` known already
        logging = ready and not self.awaiting_configuration and not get_bit(self.ow[1], OW1_STOP)
        word = status_word(self.diag_word, logging, ready, supply, self.default_config)
        if iw[2] != word:  # only what changed is written: the PLC reads it again then
            iw[2] = word
        low, high = image & 0xFFFF, image >> 16
        if iw[5] != count or iw[6] != low or iw[7] != high:
            iw[5:8] = count, low, high
        self.i_bits = input_bits(ready, count, stack.full, timebase.fault, self.pulse_image)
