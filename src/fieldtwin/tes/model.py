"""One Leroy TES remote I/O terminal: a Modbus slave device (SlaveDevice).

    >>> from fieldtwin.tes import Tes
    >>> tes = Tes("TES 8EA", slave=3)
    >>> tes.set_input("a0", 5.0)       # volts on analog input 0
    >>> tes.advance(1.0)
    >>> tes.read(0x003)                # a master read of analog input No 0, in points
    512

A ``Tes`` is composed of parts that each declare their own state: the RAM
(:class:`state.Ram`), the I/O (digital inputs, outputs, analog inputs), the
register file (the memory map of §6 over them), the master watching, the line
faults and the slave adapter (the Modbus side).  The EEPROM lives in a SQLite
:class:`ParameterStore` and is loaded into the MP words at each power-on (§1).
Sans-IO: time is the SimClock's; the public API speaks seconds.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, cast

from fieldtwin.clock import MS, S, SimClock, seconds
from fieldtwin.errors import ConfigError
from fieldtwin.hosting import host
from fieldtwin.modbus.model import Counter, LineTally, Link, Request, Result
from fieldtwin.signals import Constant
from fieldtwin.tes import state
from fieldtwin.tes.access import RegisterFile
from fieldtwin.tes.analog import AnalogInputs, AnalogSource, dac_points
from fieldtwin.tes.digital import DigitalInputs, DiscreteSource, Wiring
from fieldtwin.tes.eeprom import checked, mp_image
from fieldtwin.tes.execute import SlaveAdapter
from fieldtwin.tes.fallback import MasterWatch
from fieldtwin.tes.faults import (
    COUNT_MAX,
    LATE_MAX_MS,
    NOT_READY_WINDOW_MAX_MS,
    LineFaults,
    Param,
    number,
)
from fieldtwin.tes.inputs import (
    InputRef,
    analog_level,
    input_names,
    input_ref,
    level_note,
    parse_bool,
)
from fieldtwin.tes.kinds import Kind
from fieldtwin.tes.memmap import Register, register_names
from fieldtwin.tes.models import Family, TesModel, model_named
from fieldtwin.tes.outputs import DigitalOutputs
from fieldtwin.tes.params import Value, factory, parse_value
from fieldtwin.tes.store import ParameterStore
from fieldtwin.units import Quantity

LED = str  # "on", "off" or "blink"
_THRESHOLD_KINDS = (
    Kind.LOW_THRESHOLD,
    Kind.HIGH_THRESHOLD,
    Kind.THRESHOLD_OUTPUTS,
    Kind.THRESHOLD_POLARITY,
)


class Tes:
    """A TES of one of the ten models, with its own or a shared SimClock."""

    def __init__(
        self,
        model: str | TesModel,
        slave: int | None = None,
        *,
        clock: SimClock | None = None,
        store: str | Path | ParameterStore | None = None,
        prm_jumper: bool = False,
        name: str | None = None,
        link: Link = Link.RS485,
    ) -> None:
        self.model = model if isinstance(model, TesModel) else model_named(model)
        self.link = link  # the port this TES is reached on: ``slave`` is its number there
        # on a real RTU endpoint, replies leave when a real line would deliver them
        # (TES 7.2.7, docs/modbus.md "Wire timing"); the plant key ``wire_timing``
        self.wire_timing = True
        # issue 23: a pty master at another speed or parity gets what a UART makes of it
        # (runtime/uart.py); the plant key ``strict_line = false`` turns that off
        self.strict_line = True
        self.clock = clock if clock is not None else SimClock()
        self.name = name or f"{self.model.name} #{slave or 1}"
        self.prm_jumper = prm_jumper
        self.store = store if isinstance(store, ParameterStore) else ParameterStore(store)
        self.ram = state.Ram()
        ram = self.ram
        self.di = DigitalInputs(self.model.digital_inputs, self.clock, self._filter_ticks)
        self.do = DigitalOutputs(self.model.digital_outputs, self._blink_word)
        self.ai = AnalogInputs(
            self.model,
            self.clock,
            lambda: ram.params,
            ram.word,
            self._on_evaluate,
            self._latch_alarms,
        )
        self.line_faults = LineFaults()
        self.registers = RegisterFile(
            self.model, ram, self.di, self.do, self.ai, self._after_parameter_write
        )
        self.watch = MasterWatch(self.model, self.clock, ram, self.do)
        self.slave_adapter = SlaveAdapter(
            self.registers, ram, self.line_faults, self.watch.master_request
        )
        # a TCP session's request in one call (TcpSession: the session's fused path)
        self.fused_exchange = self.slave_adapter.exchange
        # the line-wide counts of the RTU line on each port (issue 15: once per frame)
        self._tallies: dict[str, LineTally] = {}
        self._boot(self._init_eeprom(slave))

    # --- EEPROM ------------------------------------------------------------

    def _init_eeprom(self, slave: int | None) -> dict[str, Value]:
        """The EEPROM this TES starts with (stored first when new or renumbered)."""
        stored_model = self.store.model_of(self.name)
        if stored_model is not None and stored_model != self.model.name:
            raise ConfigError(
                f"TES {self.name!r}: the parameter store {self.store.where} holds a"
                f" {stored_model}, not a {self.model.name}"
            )
        if stored_model is None and self.store.readonly:
            raise ConfigError(self.store.no_device(self.name))
        stored = self.eeprom() if stored_model is not None else None
        values = dict(stored) if stored is not None else factory(self.model)
        if slave is not None:  # §3.1.3 / §3.1.4 each port has its own slave number
            key = f"{state.link_key(self.link)}.slave"
            values[key] = parse_value(self.model, key, slave)
        if values != stored:
            self.store.save(self.name, self.model.name, values)
        return values

    def eeprom(self) -> dict[str, Value]:
        """The user settings in the EEPROM (factory values where none were written)."""
        stored = self.store.load(self.name)
        try:
            return checked(self.model, stored)
        except ConfigError as exc:
            raise ConfigError(f"{self.store.where}: device {self.name!r}: {exc}") from None

    def write_eeprom(self, values: Mapping[str, object]) -> None:
        """TESIS download: validate, write in one transaction; used at next power-on (§1)."""
        full = checked(self.model, {**self.store.load(self.name), **values})
        self.store.save(self.name, self.model.name, full)

    # --- power (§1) --------------------------------------------------------

    def power_on(self) -> None:
        """24 V on: RAM starts afresh, the MP words are loaded from the EEPROM (§1)."""
        self._boot(self.eeprom())

    def _boot(self, eeprom: dict[str, Value]) -> None:
        ram, now = self.ram, self.clock.now
        ram.booted_at = now
        # §3.1.2 the Prm jumper gives the factory settings; else the user settings
        ram.params = factory(self.model) if self.prm_jumper else eeprom
        ram.words = mp_image(self.model, ram.params)
        ram.status = state.POWER_ON
        ram.counters = {"rs485": state.LinkCounters(), "rs232": state.LinkCounters()}
        for key, tally in self._tallies.items():  # RAM lost: counting starts at 0 again
            ram.counters[key].share(tally)
        ram.ao_fallback = 0
        ram.wdg_blinking = False
        self.di.power_on(now)
        mp_command = self.model.family is Family.DIGITAL_INPUTS
        self.do.power_on(now, ram.word(0x00D) if mp_command else 0)
        self.ai.power_on(now)
        ram.powered = True
        self.watch.arm(now)
        if self.registers.safety_default():
            ram.status |= state.SAFETY

    def power_off(self) -> None:
        self.ram.powered = False
        self.di.power_off()
        self.ai.power_off()
        self.watch.stop()

    def power_cycle(self) -> None:
        """24 V off and on: RAM is lost, MP words reload from the EEPROM (§1)."""
        self.power_off()
        self.power_on()

    @property
    def powered(self) -> bool:
        return self.ram.powered

    @property
    def params(self) -> Mapping[str, Value]:
        """The settings in use since the last power-on."""
        return self.ram.params

    # --- behaviour hooks ---------------------------------------------------

    def _filter_ticks(self, value: bool) -> int:
        base = 0x01D if self.model.is_analog else 0x00A
        return self.ram.word(base + int(value))

    def _blink_word(self, i: int) -> int:
        base = {Family.DIGITAL_INPUTS: 0x00E, Family.DIGITAL_OUTPUTS: 0x007}.get(
            self.model.family, 0x01F
        )
        return self.ram.word(base + i)

    def _latch_alarms(self) -> None:
        # §6.4.1 bits 6/7 latched until the master resets them (AMB-TES-19)
        ai = self.ai
        if ai.low_mask:
            self.ram.status |= state.LOW_ALARM
        if ai.high_mask:
            self.ram.status |= state.HIGH_ALARM

    def _on_evaluate(self, now: int) -> None:
        self._latch_alarms()
        polarity = self.ram.word(0x03B)
        reflex = self.ai.reflex()
        self.do.reflex = {o: v != bool((polarity >> o) & 1) for o, v in reflex.items()}

    def _after_parameter_write(self, kind: Kind, now: int) -> None:
        if kind is Kind.WATCHDOG:
            self.watch.arm(now)
        elif kind is Kind.STORAGE_PERIOD:
            self.ai.restart_storage(now)
        elif kind in _THRESHOLD_KINDS:
            self.ai.evaluate(now)
        elif kind is Kind.CONNECTION and self.registers.safety_default():
            self.ram.status |= state.SAFETY

    # --- SlaveDevice (the Modbus side) -------------------------------------

    @property
    def slave(self) -> int:
        """The slave number on the port this TES is reached on (``link``)."""
        return self.slave_for(self.link)

    def slave_for(self, link: Link) -> int:
        value = self.ram.params[f"{state.link_key(link)}.slave"]
        assert isinstance(value, int)
        return value

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        return self.slave_adapter.execute(request, link, now, broadcast)

    def answer_delay(self, link: Link) -> int:
        """Microseconds: the port's answer delay (§3.1.3) plus a ``late_answer`` fault."""
        # the key by identity: a dict keyed by Link would hash it in Python per request
        value = self.ram.params[_RS232_DELAY if link is Link.RS232 else _RS485_DELAY]
        assert isinstance(value, int)
        return value * MS + self.line_faults.late_us

    def count(self, link: Link, counter: Counter, now: int) -> None:
        self.ram.counters["rs232" if link is Link.RS232 else "rs485"].bump(counter)

    def share_line_counts(self, link: Link, tally: LineTally) -> None:
        """The RTU line counts its line-wide counters (§6.2.3.2 01Ah-01Dh) once per frame
        on ``tally``; this TES adds them to its own (SharedLineCounts)."""
        key = state.link_key(link)
        self._tallies[key] = tally
        self.ram.counters[key].share(tally)

    def take_line_fault(self, link: Link) -> state.LineFault | None:
        """The RTU line calls this once per frame it delivers to this TES."""
        return self.line_faults.take(link)

    def status_word(self) -> int:
        return self.registers.status_word()

    def safety_default(self) -> bool:
        return self.registers.safety_default()

    # --- time (seconds) ----------------------------------------------------

    @property
    def now_s(self) -> float:
        """Simulated time in seconds."""
        return self.clock.now / S

    def advance(self, seconds_: float) -> None:
        """Let ``seconds_`` simulated seconds pass."""
        self.clock.advance(seconds(seconds_))

    def advance_to(self, seconds_: float) -> None:
        """Let simulated time reach ``seconds_`` (never back)."""
        target = seconds(seconds_)
        if target < self.clock.now:
            raise ConfigError(f"time never goes back: {seconds_:g} s < now {self.now_s:g} s")
        self.clock.run_until(target)

    # --- words: master read / write, peek ------------------------------------

    def read(self, address: int | str) -> int:
        """A master read of one word, with every side effect a read on the wire has.

        Memorized inputs are restored (§4.1.2), the watchdog is re-armed and the
        Wdg LED stops blinking (AMB-TES-10), an analog model's status bits 0
        and 1 are cleared by the exchange (§6.4.1).  Line faults do not apply.
        """
        reg = self.register(address)
        return self._exchange(lambda now: self.registers.get(reg, now))

    def peek(self, address: int | str) -> int:
        """The word as it stands, without any side effect."""
        return self.registers.peek(self.register(address), self.clock.now)

    def peek_word(self, address: int | str) -> int:
        """Older name of ``peek``."""
        return self.peek(address)

    def write(self, address: int | str, value: int) -> None:
        """A master write of one word (fc 06), with a request's side effects (see ``read``)."""
        reg = self.register(address)
        if not reg.access.writable:
            raise ConfigError(
                f"{self.model.name} word {reg.address:03X}h ({reg.name}) is read only"
            )
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFFFF:
            raise ConfigError(f"word value {value!r} out of range (allowed 0..65535)")
        self._exchange(lambda now: self.registers.put(reg, value, now))

    def _exchange(self, action: Callable[[int], int | None]) -> int:
        if not self.ram.powered:
            raise ConfigError(
                f"{self.name}: powered off, a master gets no answer (peek shows the word)"
            )
        now = self.clock.now
        self.slave_adapter.begin_exchange(self.link, now)
        value = action(now)
        self.slave_adapter.end_exchange()
        return value or 0

    def register(self, address: int | str) -> Register:
        """The documented word at ``address``, or of that name (``"analog_input[3]"``)."""
        if isinstance(address, str):
            reg = register_names(self.model).get(address.strip())
            if reg is None:
                raise ConfigError(
                    f"{self.model.name} has no word named {address!r}"
                    f" (see `fieldtwin tesis --model {self.model.name!r} map`)"
                )
            return reg
        reg = self.registers.table.get(address)
        if reg is None:
            raise ConfigError(f"{self.model.name} has no word at address {address:03X}h")
        return reg

    # --- inputs --------------------------------------------------------------

    def input_names(self) -> Mapping[str, str]:
        """name -> description: ``"0"``.. digital, ``"a0"``.. analog (docs/tes.md)."""
        return input_names(self.model)

    def _input(self, i: int | str, analog: bool) -> InputRef:
        if isinstance(i, str):
            return input_ref(self.model, i)
        return input_ref(self.model, f"a{i}" if analog else str(i))

    def set_input(self, i: int | str, value: bool | float | str | Quantity) -> str | None:
        """Digital input (bool, or an on/off word) or analog input (volts / milliamps).

        ``i`` is a name (``"3"``, ``"a2"``) or a number: with a number, a bool
        value means the digital input, a number the analog input.  An analog
        value is a number in volts or a :class:`fieldtwin.units.Quantity` in V
        or mA (§4.3.1: 0..10 V or 0..20 mA).  A level beyond the converter's
        span saturates (§4.2.4): the note saying so is returned (None otherwise).
        """
        now = self.clock.now
        ref = self._input(i, not isinstance(value, bool | str))
        if ref.analog:
            if isinstance(value, str):
                raise ConfigError(
                    f"{self.model.name} analog input {ref.name}: {value!r} is not a number"
                    ' (give a number in volts, or Quantity(3, "V") / Quantity(12, "mA"))'
                )
            level = analog_level(self.model, ref.index, value)
            note = level_note(self.model, ref.index, level)
            self.ai.set_level(ref.index, level, now)
            return note
        self.di.unfollow(ref.index)
        self.di.set_contact(ref.index, self._on_off(ref, value), now)
        return None

    def _on_off(self, ref: InputRef, value: bool | float | str | Quantity) -> bool:
        if isinstance(value, str):
            return parse_bool(value, f"{self.model.name} input {ref.name}")
        if isinstance(value, bool) or value in (0, 1):
            return bool(value)
        raise ConfigError(f"{self.model.name} input {ref.name}: {value!r} is not on or off")

    def set_signal(
        self, i: int | str, signal: AnalogSource | DiscreteSource, digital: bool | None = None
    ) -> str | None:
        """Drive an input from a fieldtwin.signals signal (value_at / next_change).

        A constant analog level beyond the converter's span returns the note of
        ``set_input``; a varying signal saturates where it leaves the span.
        """
        if digital is None and isinstance(i, int):
            digital = not self.model.analog_inputs
        ref = self._input(i, not digital)
        now = self.clock.now
        if not ref.analog:
            self.di.follow(ref.index, cast(DiscreteSource, signal), now)
            return None
        note = None
        if isinstance(signal, Constant):  # a level given as a signal
            note = level_note(self.model, ref.index, signal.value)
        self.ai.set_signal(ref.index, signal, now)
        return note

    # --- outputs -------------------------------------------------------------

    def digital_output(self, i: int) -> bool:
        return self.do.state(i, self.clock.now)

    def analog_output(self, k: int) -> float:
        """Analog output k in volts or milliamps (§4.3.1)."""
        if k not in self.model.analog_outputs:
            raise ConfigError(f"{self.model.name}: no analog output {k}")
        points = dac_points(self.ram.word(0x014 + k), self.ram.params, k)
        return points / 32767 * self.model.analog_range.full_scale

    def analog_output_word(self, k: int) -> int:
        """The word the master wrote to analog output k (§6.4.7), as it stands."""
        if k not in self.model.analog_outputs:
            raise ConfigError(f"{self.model.name}: no analog output {k}")
        return self.ram.word(0x014 + k)

    @property
    def leds(self) -> dict[str, LED]:
        """§3.1.2 front-panel LEDs: Pwr, Run, Prm (green) and Wdg (red), "on"/"off"/"blink"."""
        powered = self.ram.powered
        on = "on" if powered else "off"
        return {
            "Pwr": on,
            "Run": on,
            "Prm": "on" if self.prm_jumper and powered else "off",
            "Wdg": "blink" if self.ram.wdg_blinking and powered else "off",  # §3.1.3
        }

    # --- faults by name (docs/tes.md): each kind's table, through the host ----

    def fault_names(self) -> Mapping[str, str]:
        """name -> description of every fault this core takes by name."""
        return cast(Any, host()).fault_names(self)  # type: ignore[no-any-return]

    fault_names.through_table = True  # type: ignore[attr-defined]  # (devices.faults)

    def inject_fault(self, name: str, on: bool, **params: int | float) -> None:
        """Set or clear a fault by its name: the kind's table (fieldtwin.devices) maps
        it to this core's typed call; ConfigError naming what is allowed."""
        cast(Any, host()).inject_fault(self, name, on, **params)

    # --- faults --------------------------------------------------------------

    def active_faults(self) -> dict[str, dict[str, Param]]:
        """The faults in force, each with its parameters, by the names of docs/tes.md."""
        out: dict[str, dict[str, Param]] = {}
        if self.model.safety:
            for i in range(self.model.digital_inputs):
                wiring = self.di.wiring(i)
                if wiring is not Wiring.OK:
                    out[f"{wiring.value}_{i}"] = {}
        if not self.powered:
            out["power_off"] = {}
        out.update(self.line_faults.active())
        return out

    def set_no_answer(self, on: bool) -> None:
        """The TES hears nothing: requests are neither executed nor answered."""
        self.line_faults.no_answer = bool(on)

    def set_late_answer(self, ms: float) -> None:
        """Every answer leaves ``ms`` (0..60 000) later than the answer delay; 0: on time."""
        self.line_faults.late_us = round(number("ms", ms, 0, LATE_MAX_MS, " ms") * MS)

    def set_corrupt_frames(
        self, fault: state.LineFault, on: bool, count: int | None = None
    ) -> None:
        """Frames to this TES arrive with ``fault`` (a CRC error, a wrong character):
        every frame until cleared (``count`` None), or the next ``count`` only."""
        if count is not None:
            count = int(number("count", count, 1, COUNT_MAX))
        self.line_faults.set_corrupt(state.LineFault(fault), on, count, self.link)

    def set_not_ready(
        self, on: bool, count: int | None = None, window_ms: float | None = None
    ) -> None:
        """Requests in the 32-bit area get exception 4 "slave not ready": every one
        (neither given), the next ``count``, or during ``window_ms`` of each 100 ms refresh."""
        window = None
        if window_ms is not None:
            ms = number("window_ms", window_ms, 0, NOT_READY_WINDOW_MAX_MS, " ms")
            if ms >= NOT_READY_WINDOW_MAX_MS:
                raise ConfigError(
                    f"fault parameter window_ms: {ms!r} not allowed (allowed 0..<100 ms)"
                )
            window = round(ms * MS)
        if count is not None:
            count = int(number("count", count, 1, COUNT_MAX))
        self.line_faults.set_not_ready(on, count, window)

    def drop_connections(self) -> int:
        """Close every TCP connection this TES is reached through now; how many closed."""
        if not self.line_faults.droppers:
            raise ConfigError(
                "fault 'drop_connections': this TES is not served on a TCP endpoint"
                " (tcp:// or rtu+tcp://) by this run"
            )
        return sum(drop() for drop in list(self.line_faults.droppers))

    def set_wiring(self, i: int, wiring: Wiring | str) -> None:
        """TES 32ET-S: a short circuit or a broken wire on input ``i`` (§4.1.5)."""
        if not self.model.safety:
            raise ConfigError(f"{self.model.name} has no safety inputs (only the TES 32ET-S)")
        try:
            w = Wiring(wiring)
        except ValueError:
            raise ConfigError(f"wiring {wiring!r} not allowed (allowed: ok, short, open)") from None
        self.di.set_wiring(self._input(i, False).index, w, self.clock.now)
        if self.registers.safety_default():
            self.ram.status |= state.SAFETY  # §6.2.1 bit 2, reset by the master

    def inject_not_ready(self, count: int = 1) -> None:
        """The next ``count`` requests in the 32-bit area get "slave not ready"."""
        self.line_faults.not_ready_left += count

    @property
    def not_ready_window_us(self) -> int:
        """Each 100 ms, "slave not ready" in the 32-bit area for this long (0: never)."""
        return self.line_faults.not_ready_window_us

    @not_ready_window_us.setter
    def not_ready_window_us(self, value: int) -> None:
        self.line_faults.not_ready_window_us = value

    def inject_line_fault(
        self, fault: state.LineFault | str, count: int = 1, link: Link = Link.RS485
    ) -> None:
        """Ask the line glue to corrupt the next ``count`` frames to this TES."""
        try:
            kind = state.LineFault(fault)
        except ValueError:
            raise ConfigError(
                f"line fault {fault!r} not allowed (allowed: bad_crc, broken_character)"
            ) from None
        self.line_faults.queue(kind, count, link)


_RS232_DELAY, _RS485_DELAY = state.RS232_DELAY, state.RS485_DELAY  # by identity, per request
