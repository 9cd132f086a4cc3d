"""The TSX DEM 2412 / 2413 time-stamping module (the manual tsx-dem-24-time-stamping.txt).

Sans-IO and event-driven: the module acts at input edges (from the signals' next
change), at the ends of the input filters, at synchronization pulses, at the
pulse-loss deadline, at oscillation checks and at periodic logging; nothing runs per
PLC scan.  The Text Block requests live in :mod:`fieldtwin.tsx.dem24.requests`, the
console and plant-file side and the two models in :mod:`fieldtwin.tsx.dem24.models`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from fieldtwin.clock import Handle
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.dem24 import requests
from fieldtwin.tsx.dem24.config import (
    DEFAULT_CONFIG,
    FB_CONFIG_REFUSED,
    FB_SUPPLY,
    FB_SYNC,
    FB_TERMINAL,
    Dem24Config,
)
from fieldtwin.tsx.dem24.inputs import (
    CHANNELS,
    TYPE1_24V,
    InputBank,
    InputSignal,
    Thresholds,
    check_channel,
)
from fieldtwin.tsx.dem24.logbook import OW1_OVERALL, OW1_PURGE, Logbook
from fieldtwin.tsx.dem24.oscillation import Detector
from fieldtwin.tsx.dem24.oscillation import Thresholds as OscThresholds
from fieldtwin.tsx.dem24.stack import (
    CH_SUPPLY,
    CH_SYNC,
    CH_TERMINAL,
    STATE_OSCILLATING,
    MessageStack,
)
from fieldtwin.tsx.dem24.sync import SYNC_OUTPUT_MAX, PulseSource
from fieldtwin.tsx.dem24.timebase import SyncOutcome, Timebase
from fieldtwin.tsx.module import FaultCategory, ModuleContext, ModuleState
from fieldtwin.tsx.textblock import Exchange
from fieldtwin.words import get_bit


class Dem24Core(Logbook):
    """The time-stamping function; :class:`Dem24` adds the console and plant-file side."""

    type_name: ClassVar[str] = "TSX DEM 24"
    thresholds: ClassVar[Thresholds] = TYPE1_24V
    fault_string_bytes = 12  # DEM 4.3: 96 bits
    terminal_block_fault_bit = FB_TERMINAL

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
        self.timebase = Timebase(drift_ppm=self.clock_drift_ppm)
        self.stack = MessageStack()
        self.inputs = InputBank(self.clock, self.thresholds, self._stamp, self._accepted)
        self.detectors: list[Detector] | None = None
        self._osc_handles: list[Handle | None] = [None] * CHANNELS
        self._loss: Handle | None = None
        self._periodic: Handle | None = None
        self._periodic_due_ms: int | None = None
        self.pulse_image = False
        self.terminal_block = True  # fitted
        self.supply = True  # external supply present
        self.sync_outputs: list[Dem24Core] = []
        self.pulse_source: PulseSource | None = None
        self.plant_startup: list[Any] = []  # requests the plant file applies after self-test
        self.edges_stamped = 0

    # --- public API: inputs and pulses ------------------------------------------------

    def set_input(self, channel: int, *args: Any, **kwargs: Any) -> None:
        """``set_input(channel, value)``: a bool, or volts judged as IEC 61131-2 type 1."""
        value = args[0] if args else kwargs.get("value")
        if value is None:
            raise ConfigError("set_input(channel, value): value missing (a bool or volts)")
        self.inputs.set_value(check_channel(channel), value, self.clock.now)

    def set_signal(self, channel: int, signal: InputSignal | None) -> None:
        """Drive an input from a signal (bools, or volts switched where they cross a limit)."""
        self.inputs.attach(check_channel(channel), signal)

    def sync_pulse(self) -> None:
        """One synchronization pulse on IN-SYN now."""
        self.receive_pulse(self.clock.now)

    def connect_sync_output(self, other: Dem24Core) -> None:
        """Wire OUT-SYN to another module's IN-SYN (at most 32, DEM 7.2)."""
        if len(self.sync_outputs) >= SYNC_OUTPUT_MAX:
            raise ConfigError(
                f"sync output of slot {self.address} already drives {SYNC_OUTPUT_MAX} modules"
                " (allowed at most 32)"
            )
        if other is self or other in self.sync_outputs:
            raise ConfigError(f"slot {other.address} cannot be wired twice or to itself")
        self.sync_outputs.append(other)

    def attach_pulse_source(self, period_us: int, start_us: int = 0) -> PulseSource:
        """An external pulse generator on IN-SYN (replaces any previous one)."""
        if self.pulse_source is not None:
            self.pulse_source.stop()
        self.pulse_source = PulseSource(self.clock, period_us, start_us, self.receive_pulse)
        return self.pulse_source

    def set_clock_drift(self, ppm: float) -> None:
        """Make the module clock fast (> 0) or slow by ``ppm`` (DEM 7.2: within 25 ppm)."""
        self.clock_drift_ppm = float(ppm)
        self.timebase.clock.set_drift(self.clock_drift_ppm, self.clock.now)
        self._arm_periodic(self.clock.now)

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
        self.timebase = Timebase(drift_ppm=self.clock_drift_ppm)
        self.stack = MessageStack()
        self.detectors = None
        self._osc_handles = [None] * CHANNELS
        self._periodic_due_ms = None
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
        self.timebase.t_syn_ms, self.timebase.drift_ms = config.t_syn_s * 1000, config.drift_ms
        self.inputs.set_filter_ms(config.filt_ms)
        for handle in self._osc_handles:
            if handle is not None:
                handle.cancel()
        self._osc_handles = [None] * CHANNELS
        self.detectors = None
        if config.oscillation:
            th = OscThresholds.from_config(
                config.t_max_s, config.n_max, config.t_min_s, config.n_min
            )
            self.detectors = [Detector(th) for _ in range(CHANNELS)]
        monitored = config.supply_monitoring and not self.supply
        if monitored != self.fault_active(FB_SUPPLY):
            self._fault_input(FB_SUPPLY, CH_SUPPLY, monitored)
        self._start_periodic(now)
        self.refresh_status()
        self._refresh_words()

    def refuse_config(self, diag_word: int) -> None:
        """DEM 3.4-3: awaiting configuration, diagnostic bits, time-stamping stops."""
        self.awaiting_configuration = True
        self.diag_word = diag_word
        self.set_fault(FB_CONFIG_REFUSED, True)
        self._refresh_words()

    # --- time -----------------------------------------------------------------------

    def receive_pulse(self, now: int) -> None:
        """IN-SYN pulse: repeated on OUT-SYN, then taken by the time base (DEM 4.1-3)."""
        if self.state is ModuleState.OFF:
            return
        for other in self.sync_outputs:
            other.receive_pulse(now)
        if self.state is not ModuleState.OPERATIONAL:
            return
        self.pulse_image = not self.pulse_image  # DEM 2.4-2 note: Ixy,7 changes at each pulse
        self._sync_outcome(self.timebase.pulse(now), now)
        self._arm_loss()
        self._arm_periodic(now)  # the pulse may have reset the module clock

    def _arm_loss(self) -> None:
        if self._loss is not None:
            self._loss.cancel()
            self._loss = None
        deadline = self.timebase.loss_deadline()
        if deadline is not None:
            self._loss = self.call_at(deadline, self._pulse_lost)

    def _pulse_lost(self, now: int) -> None:
        self._loss = None
        self._sync_outcome(self.timebase.pulse_lost(now), now)

    def _sync_outcome(self, outcome: SyncOutcome, now: int) -> None:
        if outcome.fault is not None:
            self.set_fault(FB_SYNC, outcome.fault)  # DEM 4.3: application fault, ERR LED
            self._log_change(CH_SYNC, int(outcome.fault), self._stamp(now))
        if outcome.time_set:
            self.log_overall(now)  # DEM 4.2-3: first message after the time is set
            self._start_periodic(now)  # PER counted in module time from the time setting
        self._refresh_words()

    # --- inputs -------------------------------------------------------------------------

    def _accepted(self, channel: int, level: bool, edge: int, stamp: int | None, now: int) -> None:
        self.edges_stamped += 1
        state = int(level)
        detector = self.detectors[channel] if self.detectors is not None else None
        if detector is not None:
            if detector.transition(edge):
                state = STATE_OSCILLATING  # DEM 2.3-3: shown to be oscillating
            elif detector.oscillating:
                state = -1  # DEM 2.3-3: its transitions are no longer indicated
            self._schedule_osc_check(channel)
        if state >= 0:
            self._log_change(channel, state, stamp)
        self._refresh_words()

    def _schedule_osc_check(self, channel: int) -> None:
        handle = self._osc_handles[channel]
        if handle is not None:
            handle.cancel()
        assert self.detectors is not None
        at = self.detectors[channel].next_check()
        self._osc_handles[channel] = (
            None if at is None else self.call_at(at, lambda now: self._osc_check(channel, now))
        )

    def _osc_check(self, channel: int, now: int) -> None:
        self._osc_handles[channel] = None
        assert self.detectors is not None
        if self.detectors[channel].check(now):  # normal again: its state (AMB-DEM-11)
            self._log_change(channel, int(self.inputs.level(channel)), self._stamp(now))
            self._refresh_words()
        else:
            self._schedule_osc_check(channel)

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
            self._log_change(channel, int(active), self._stamp(now))  # AMB-DEM-19
        self._update_reading(now)
        self._refresh_words()
