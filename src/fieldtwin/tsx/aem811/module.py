"""The TSX AEM 811 analog input module twin.

AEM 2.2-4 / 4.1: one event per 100 ms acquisition slot of an enabled channel:
the input is sampled when its slot begins and the measurement reaches its
register word 100 ms later, with the IWxy,2,0..3 selector telling channel k
from channel k + 4.  AEM 2.3: ranges, square root, scaling, ELL/EHL, the
continuity test, thresholds with hysteresis.  AEM 3: configuration.  AEM 4.2,
4.3, 4.4: the requests.  Nothing runs per PLC scan.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Protocol

from fieldtwin.clock import Handle, S
from fieldtwin.errors import ConfigError
from fieldtwin.signals.base import AnalogSignal
from fieldtwin.tsx.aem811 import faults as flt
from fieldtwin.tsx.aem811 import requests
from fieldtwin.tsx.aem811.config import DEFAULT_CONFIG, ModuleConfig, Rejection
from fieldtwin.tsx.aem811.inputs import UNITS, ChannelInput, electrical
from fieldtwin.tsx.aem811.scaling import Measurement, hysteresis, measure
from fieldtwin.tsx.aem811.sequencer import SLOT_US, Sequencer, Slot
from fieldtwin.tsx.aem811.thresholds import ThresholdDetector
from fieldtwin.tsx.module import FaultCategory, IntelligentModule, ModuleContext, ModuleState
from fieldtwin.tsx.textblock import (
    V_OK_WRITE,
    Answer,
    Exchange,
)
from fieldtwin.words import set_bit

ACCELERATED_BIT = 8  # OWxy,1,8
DEFAULT_CONFIG_BIT = 0xD  # IWxy,2,D


class Startup(Protocol):
    """A plant file's configuration, applied when the initial self-test ends."""

    def apply(self, mod: Aem811) -> None: ...


@dataclass(frozen=True, slots=True)
class _Acquisition:
    """A slot in progress: what was sampled when it began."""

    channel: int
    start: int
    mv: float | None
    tested: bool


class Aem811(IntelligentModule):
    """8 analog inputs, 9 ranges, 3 scalings, 2 thresholds a channel (TSX AEM 811)."""

    type_name: ClassVar[str] = "TSX AEM 811"
    hardware_codes: ClassVar[frozenset[int]] = frozenset({648})  # AEM 6.1-3
    software_codes: ClassVar[frozenset[int]] = frozenset({62})  # TSX 47-20 (AMB-AEM-15)
    self_test_us: ClassVar[int] = 10 * S  # AEM 7.1-1
    fault_string_bytes: ClassVar[int] = 8  # AEM 4.4-1: 64 bits (AMB-AEM-05)
    version_text: ClassVar[str] = "TSX AEM 811 V1.0"
    terminal_block_fault_bit: ClassVar[int | None] = flt.TERMINAL_BLOCK

    def __init__(
        self,
        ctx: ModuleContext,
        rack: int,
        slot: int,
        *,
        declared_code: int | None = None,
        quantize: bool = True,
    ) -> None:
        super().__init__(ctx, rack, slot, declared_code=declared_code)
        self.quantize = quantize
        self.inputs = [ChannelInput() for _ in range(8)]
        self.cut = [False] * 8  # injected wire cuts (fault "open_N")
        self.relay_operations = [0] * 8
        self._startup: Startup | None = None
        # the volatile memory (AEM 2.5-3): reset by _reset_volatile at power-up and off
        self.config: ModuleConfig = DEFAULT_CONFIG
        self.default_configuration = True
        self.rejection: Rejection | None = None
        self.thresholds = ThresholdDetector()
        self.values = [0] * 8  # latest measurement of each channel
        self.snapshot = [0] * 8  # AEM 4.2: the last complete cycle, for request 1
        self.registers = [0] * 4  # IWxy,3..6 in the module
        self.selector = 0  # IWxy,2,0..3
        self.measurements: list[Measurement | None] = [None] * 8
        self.hysteresis_values = [hysteresis(c) for c in self.config.channels]
        self._acquiring: _Acquisition | None = None
        self._event: Handle | None = None
        self._sequencer: Sequencer | None = None
        self._channel_faults = 0  # IWxy,1,8..F: live, not memorised
        self.run_started_at_us: int | None = None  # when acquisition last started
        self.pending_thresholds: Exchange | None = None

    def _reset_volatile(self) -> None:
        # AEM 2.5-3: no protected memory; power-up restarts with the defaults
        self.config = DEFAULT_CONFIG
        self.default_configuration = True
        self.rejection = None
        self.thresholds = ThresholdDetector()
        self.values = [0] * 8
        self.snapshot = [0] * 8
        self.registers = [0] * 4
        self.selector = 0
        self.measurements = [None] * 8
        self.hysteresis_values = [hysteresis(c) for c in self.config.channels]
        self._acquiring = None
        self._event = None
        self._sequencer = None
        self._channel_faults = 0
        self.run_started_at_us = None
        self.pending_thresholds = None

    # --- inputs (API names fixed: tests outside the project use them) ---------

    def set_input(
        self,
        channel: int,
        *,
        volts: float | None = None,
        milliamps: float | None = None,
        open_circuit: bool = False,
    ) -> None:
        """The electrical value on a channel: volts, milliamps (100 ohm) or open."""
        self._check_channel(channel)
        self.inputs[channel] = electrical(
            volts=volts, milliamps=milliamps, open_circuit=open_circuit
        )

    def set_signal(self, channel: int, signal: AnalogSignal, unit: str = "auto") -> None:
        """A signal on a channel, in volts, milliamps, or "auto" (the range's unit)."""
        self._check_channel(channel)
        if unit not in UNITS:
            raise ConfigError(f"unit {unit!r} not allowed (allowed: {', '.join(UNITS)})")
        self.inputs[channel] = ChannelInput(unit, 0.0, signal)

    def set_level(self, channel: int, value: float) -> None:
        """A number in the unit of the channel's range (mA on 0/20 and 4/20 mA, V otherwise)."""
        self._check_channel(channel)
        checked = electrical(volts=value)  # a finite number
        self.inputs[channel] = ChannelInput("auto", checked.value)

    @staticmethod
    def _check_channel(channel: int) -> None:
        if isinstance(channel, bool) or not isinstance(channel, int) or not 0 <= channel <= 7:
            raise ConfigError(f"channel {channel!r} not allowed (allowed 0..7)")

    def _sample(self, channel: int, now: int) -> float | None:
        if self.cut[channel]:
            return None
        current = self.config.channels[channel].range.current
        return self.inputs[channel].millivolts(now, current)

    @property
    def run_started_at(self) -> float | None:
        """Simulated seconds when acquisition last started (None in Stop)."""
        return None if self.run_started_at_us is None else self.run_started_at_us / S

    # --- command words -------------------------------------------------------

    @property
    def enabled(self) -> int:
        """Mask of the channels in Run: OWxy,1,i = 0 (AEM 2.5-2)."""
        return ~self.ow[1] & 0xFF

    @property
    def accelerated(self) -> bool:
        return bool(self.ow[1] >> ACCELERATED_BIT & 1)

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        old = old_ow[1]
        if old == self.ow[1]:
            return
        newly_inhibited = ~old & self.ow[1] & 0xFF
        for channel in range(8):
            if newly_inhibited >> channel & 1:
                self._inhibit(channel)
        if self._sequencer is not None:
            self._commands_changed(old, now)
        self.refresh_words()

    def _inhibit(self, channel: int) -> None:
        # AEM 2.2-4, 4.1-2, 4.3-2: not sampled, value 0, bits 0, not in its register
        self.values[channel] = 0
        self.measurements[channel] = None
        self.thresholds.force_off(channel)
        self.i_bits = self.thresholds.bits
        self._set_channel_faults(channel, Measurement(0))
        index, partner = channel & 3, channel ^ 4
        if (self.selector >> index & 1) == (channel >> 2):
            if self.enabled >> partner & 1:
                self.registers[index] = self.values[partner]
                self.selector = set_bit(self.selector, index, partner >> 2)
            else:
                self.registers[index] = 0
        if self._acquiring is not None and self._acquiring.channel == channel:
            self._cancel_event()
            self._acquiring = None

    def _commands_changed(self, old: int, now: int) -> None:
        sequencer = self._sequencer
        assert sequencer is not None
        if bool(old >> ACCELERATED_BIT & 1) != self.accelerated:
            sequencer.accelerated = self.accelerated  # AEM 4.1-4: OWxy,1,8
            restart = self._acquiring.start + SLOT_US if self._acquiring else now
            sequencer.restart(restart)
        if self._acquiring is None:
            self._cancel_event()
            self._next_slot(now)

    # --- Run / Stop and the acquisition events --------------------------------

    def on_run_changed(self, running: bool, now: int) -> None:
        self._cancel_event()
        self._acquiring = None
        if not running:  # AEM 4.1-2: the registers keep the last values
            self._sequencer = None
            self.run_started_at_us = None
            return
        self.run_started_at_us = now
        period = self.config.period * SLOT_US
        self._sequencer = Sequencer(period, self.accelerated, now)
        self._next_slot(now)

    def _cancel_event(self) -> None:
        if self._event is not None:
            self._event.cancel()
            self._event = None

    def _next_slot(self, now: int) -> None:
        """Begin the next slot now, or wait for it (nothing at all if none is enabled)."""
        sequencer = self._sequencer
        assert sequencer is not None
        slot = sequencer.next_slot(now, self.enabled)
        if slot is None:
            self.ack_thresholds(now)  # nothing to compare with: acknowledge at once
            return
        if slot.cycle_ended:
            self._end_of_cycle()
        if slot.start > now:
            self._event = self.call_at(slot.start, self._next_slot)
            return
        self._begin(slot, now)

    def _begin(self, slot: Slot, now: int) -> None:
        assert self._sequencer is not None
        self._sequencer.begin(slot)
        channel = slot.channel
        cfg = self.config.channels[channel]
        tested = cfg.continuity and not self.accelerated  # manual-notes: normal mode only
        self.relay_operations[channel] += 1  # AEM 2.5-2 relay life
        self._acquiring = _Acquisition(channel, now, self._sample(channel, now), tested)
        self._event = self.call_at(now + SLOT_US, self._end_slot)

    def _end_slot(self, now: int) -> None:
        done, self._acquiring = self._acquiring, None
        if done is not None:
            self._publish(done, now)
        self._next_slot(now)

    def _publish(self, done: _Acquisition, now: int) -> None:
        """AEM 4.1-4: the value reaches its register 100 ms after acquisition."""
        self.ack_thresholds(now)  # AEM 4.3-1: acknowledged once compared
        channel = done.channel
        cfg = self.config.channels[channel]
        m = measure(done.mv, cfg, quantize=self.quantize, tested=done.tested)
        self.values[channel] = m.value
        self.measurements[channel] = m
        index = channel & 3
        self.registers[index] = m.value
        self.selector = set_bit(self.selector, index, channel >> 2)
        self.thresholds.compare(channel, m.value, self.hysteresis_values[channel])
        self.i_bits = self.thresholds.bits
        self._set_channel_faults(channel, m)
        self.refresh_words()

    def _end_of_cycle(self) -> None:
        """AEM 2.2-4 / 4.2: the message-mode measurements all come from one cycle."""
        enabled = self.enabled
        self.snapshot = [v if enabled >> c & 1 else 0 for c, v in enumerate(self.values)]

    # --- faults ----------------------------------------------------------------

    def _set_channel_faults(self, channel: int, m: Measurement) -> None:
        for bit, active in zip(flt.channel_bits(channel), flt.conditions(m), strict=True):
            if self.fault_active(bit) != active:
                self.set_fault(bit, active, FaultCategory.APPLICATION)
        self._channel_faults = set_bit(self._channel_faults, channel, m.faulty)

    # --- requests (AEM 4.2, 4.3, 3.4, 4.4) -------------------------------------------

    def handle_request(self, exchange: Exchange, now: int) -> None:
        requests.handle(self, exchange, now)

    def ack_thresholds(self, now: int) -> None:
        """AEM 4.3-1: install the written thresholds and acknowledge with H'FE'."""
        exchange, self.pending_thresholds = self.pending_thresholds, None
        if exchange is None:
            return
        level = 0 if exchange.request.code == requests.WRITE_T0 else 1
        self.thresholds.write_table(level, exchange.request.data)
        exchange.complete(Answer(V_OK_WRITE), now)

    def on_exchange_cancelled(self, exchange: Exchange, now: int) -> None:
        if exchange is self.pending_thresholds:
            self.pending_thresholds = None

    def fault_category_of(self, bit: int) -> FaultCategory:
        return flt.category(bit)

    # --- conditions put on the module (the faults of docs/aem811.md) ------------------

    def set_wire_break(self, channel: int, cut: bool) -> None:
        """Channel ``channel``'s wire cut (an open circuit at the input) or mended."""
        self._check_channel(channel)
        self.cut[channel] = cut

    def set_terminal_block(self, fitted: bool) -> None:
        """The terminal block fitted or open (bit 16, IWxy,0,A: module to Stop)."""
        self.hardware_fault(flt.TERMINAL_BLOCK, not fitted)

    def set_converter_fault(self, present: bool) -> None:
        """The analog to digital converter failed (bit 17: module to Stop)."""
        self.hardware_fault(flt.CONVERTER, present)

    def set_processor_fault(self, present: bool) -> None:
        """Processor or bus interface failure: blocking fault, F LED, until power-up."""
        self.hardware_fault(flt.PROCESSOR, present)

    def set_relay_fault(self, present: bool) -> None:
        """An input relay failed (bit 18): only the next initial self-test finds it
        (AEM 7.1-1); repaired, the bit is cleared at once."""
        (self._hardware_faults.add if present else self._hardware_faults.discard)(flt.RELAY)
        if not present:
            self.set_fault(flt.RELAY, False)

    # --- power and self-test -----------------------------------------------------

    def on_power_on(self, now: int) -> None:
        self._reset_volatile()
        self.refresh_words()

    def on_power_off(self, now: int) -> None:
        self._reset_volatile()

    def on_blocked(self, now: int) -> None:
        self._cancel_event()
        self._acquiring, self._sequencer = None, None
        # AEM 4.4-1: a blocked module makes no exchange; what it held (a threshold
        # write, a request sent during the self-test) was ended by the base (module fault)
        self.pending_thresholds = None

    def on_self_test_done(self, now: int) -> None:
        self.refresh_words()
        if self._startup is not None:
            startup, self._startup = self._startup, None
            startup.apply(self)

    # --- register words ------------------------------------------------------------

    def refresh_words(self) -> None:
        """IWxy,1..7 from the module's state (IWxy,0 is the base's)."""
        self.iw[1] = (self.ow[1] & 0xFF) | self._channel_faults << 8  # AEM 4.4-1 IWxy,1
        self.iw[2] = self.selector | int(self.default_configuration) << DEFAULT_CONFIG_BIT
        self.iw[3:7] = [r & 0xFFFF for r in self.registers]
        self.iw[7] = 0

    # --- plant file and status -------------------------------------------------------

    def schedule_startup(self, startup: Startup) -> None:
        """Plant-file configuration: applied when the initial self-test ends."""
        if self.state is ModuleState.OPERATIONAL and not self.running:
            startup.apply(self)
        else:
            self._startup = startup
