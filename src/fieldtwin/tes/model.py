"""One Leroy TES remote I/O terminal: a Modbus slave device (SlaveDevice).

    >>> from fieldtwin.tes import Tes
    >>> tes = Tes("TES 8EA", slave=3)
    >>> tes.set_input(0, 5.0)          # volts on analog input 0
    >>> tes.advance(1.0)
    >>> tes.read(0x003)                # analog input No 0, in points
    512

The memory map (§6) is data in :mod:`fieldtwin.tes.memmap`; the EEPROM lives
in a SQLite :class:`ParameterStore` and is loaded into the MP words at each
power-on (§1).  Sans-IO: time is the SimClock's.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import cast

from fieldtwin.clock import MS, Handle, SimClock, seconds
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Counter, Link
from fieldtwin.tes import state
from fieldtwin.tes.access import RegisterFile
from fieldtwin.tes.analog import AnalogInputs, AnalogSource, dac_points
from fieldtwin.tes.digital import DigitalInputs, Wiring
from fieldtwin.tes.drivers import DiscreteDriver, DiscreteSource
from fieldtwin.tes.eeprom import checked, mp_image
from fieldtwin.tes.execute import ModbusSlave
from fieldtwin.tes.memmap import Register, memory_map
from fieldtwin.tes.models import Family, TesModel, model_named
from fieldtwin.tes.outputs import DigitalOutputs
from fieldtwin.tes.params import Value, factory, parse_value
from fieldtwin.tes.store import ParameterStore

WATCHDOG_BASE = 100 * MS  # §6.2.3.1 Tb = 100 ms


class Tes(RegisterFile, ModbusSlave):
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
        self.clock = clock if clock is not None else SimClock()
        self.name = name or f"{self.model.name} #{slave or 1}"
        self.prm_jumper = prm_jumper
        self.store = store if isinstance(store, ParameterStore) else ParameterStore(store)
        self.registers: dict[int, Register] = {r.address: r for r in memory_map(self.model)}
        self.di = DigitalInputs(self.model.digital_inputs, self.clock, self._filter_ticks)
        self.do = DigitalOutputs(self.model.digital_outputs, self._blink_word)
        self.ai = AnalogInputs(
            self.model, self.clock, lambda: self.params, self._word, self._on_evaluate
        )
        self._drivers: dict[int, DiscreteDriver] = {}
        self._watchdog: Handle | None = None
        self.init_slave()
        self._init_eeprom(slave)
        self.powered = False
        self.power_on()

    # --- EEPROM ------------------------------------------------------------

    def _init_eeprom(self, slave: int | None) -> None:
        stored_model = self.store.model_of(self.name)
        if stored_model is not None and stored_model != self.model.name:
            raise ConfigError(
                f"TES {self.name!r}: the parameter store holds a {stored_model},"
                f" not a {self.model.name}"
            )
        values = self.eeprom() if stored_model is not None else factory(self.model)
        if slave is not None:  # §3.1.3 / §3.1.4 each port has its own slave number
            key = f"{state.link_key(self.link)}.slave"
            values[key] = parse_value(self.model, key, slave)
        if stored_model is None or values != self.eeprom():
            self.store.save(self.name, self.model.name, values)

    def eeprom(self) -> dict[str, Value]:
        """The user settings in the EEPROM (factory values where none were written)."""
        return checked(self.model, self.store.load(self.name))

    def write_eeprom(self, values: Mapping[str, object]) -> None:
        """TESIS download: validate, write in one transaction; used at next power-on (§1)."""
        full = checked(self.model, {**self.store.load(self.name), **values})
        self.store.save(self.name, self.model.name, full)

    # --- power (§1) --------------------------------------------------------

    def power_on(self) -> None:
        now = self.booted_at = self.clock.now
        # §3.1.2 the Prm jumper gives the factory settings; else the user settings
        self.params = factory(self.model) if self.prm_jumper else self.eeprom()
        self.words = mp_image(self.model, self.params)
        self.status = state.POWER_ON
        self.counters = {"rs485": state.LinkCounters(), "rs232": state.LinkCounters()}
        self.ao_fallback = 0
        self.wdg_blinking = False
        self.di.power_on(now)
        self.do.power_on(now, self.words.get(0x00D, 0) if self._mp_command() else 0)
        self.ai.power_on(now)
        self.powered = True
        self._arm_watchdog(now)
        if self.model.safety and self.safety_default():
            self.status |= state.SAFETY

    def _mp_command(self) -> bool:
        return self.model.family is Family.DIGITAL_INPUTS

    def power_off(self) -> None:
        self.powered = False
        self.di.power_off()
        self.ai.power_off()
        if self._watchdog is not None:
            self._watchdog.cancel()
            self._watchdog = None

    def power_cycle(self) -> None:
        """24 V off and on: RAM is lost, MP words reload from the EEPROM (§1)."""
        self.power_off()
        self.power_on()

    # --- master watching and fallback (§3.1.3, §4.1.7, §6.4.11) ------------

    def _watchdog_address(self) -> int:
        return 0x03C if self.model.is_analog else 0x016

    def _arm_watchdog(self, now: int) -> None:
        if self._watchdog is not None:
            self._watchdog.cancel()
            self._watchdog = None
        period = self.words.get(self._watchdog_address(), 0) * WATCHDOG_BASE
        if period and self.powered:
            self._watchdog = self.clock.schedule(now + period, self._fall_back)

    def master_request(self, link: Link, now: int) -> None:
        """AMB-TES-10: a request to this slave (or broadcast) on RS-485 re-arms the watchdog."""
        self.wdg_blinking = False
        if link is not Link.RS232:
            self._arm_watchdog(now)

    def _fall_back(self, now: int) -> None:
        self._watchdog = None
        self.status |= state.FALLBACK
        self.wdg_blinking = True  # §3.1.3 "led Wdg will blinking"
        if self.model.is_analog:
            self._analog_fall_back()
            return
        w = self.words
        if self.model.family is Family.DIGITAL_OUTPUTS:
            or_ = (w[0x00E] | w[0x00F] << 16, w[0x010] | w[0x011] << 16)
            and_ = (w[0x012] | w[0x013] << 16, w[0x014] | w[0x015] << 16)
        else:
            or_, and_ = (w[0x012], w[0x013]), (w[0x014], w[0x015])
        self.do.fall_back(or_, and_)
        self._sync_command()

    def _analog_fall_back(self) -> None:
        # §6.4.11.2 same layout as the command word; reflex outputs do not fall back
        command = self.words[0x03D]
        self.do.blink_select, self.do.command = (command >> 8) & 0xF, command & 0xF
        enable = self.words[0x046]
        for k in self.model.analog_outputs:  # §6.4.11.3 authorised outputs only
            if (enable >> k) & 1:
                self.words[0x014 + k] = self.words[0x03E + k]
                self.ao_fallback |= 1 << k

    def _sync_command(self) -> None:
        if self._mp_command():
            self.words[0x00D] = self.do.command & 0xFFFF

    # --- behaviour hooks ---------------------------------------------------

    def _filter_ticks(self, value: bool) -> int:
        base = 0x01D if self.model.is_analog else 0x00A
        return self.words.get(base + int(value), 0)

    def _blink_word(self, i: int) -> int:
        base = {Family.DIGITAL_INPUTS: 0x00E, Family.DIGITAL_OUTPUTS: 0x007}.get(
            self.model.family, 0x01F
        )
        return self.words.get(base + i, 0)

    def _word(self, address: int) -> int:
        return self.words.get(address, 0)

    def _on_evaluate(self, now: int) -> None:
        # §6.4.1 bits 6/7 latched until the master resets them (AMB-TES-19)
        channels = self.ai.channels.values()
        if any(ch.low for ch in channels):
            self.status |= state.LOW_ALARM
        if any(ch.high for ch in channels):
            self.status |= state.HIGH_ALARM
        polarity = self.words.get(0x03B, 0)
        reflex = self.ai.reflex()
        self.do.reflex = {o: v != bool((polarity >> o) & 1) for o, v in reflex.items()}

    def after_parameter_write(self, kind: str, now: int) -> None:
        if kind == "watchdog":
            self._arm_watchdog(now)
        elif kind == "storage_period":
            self.ai.restart_storage(now)
        elif kind in ("low_threshold", "high_threshold", "threshold_outputs", "threshold_polarity"):
            self.ai.evaluate(now)
        elif kind == "connection" and self.safety_default():
            self.status |= state.SAFETY

    # --- public API --------------------------------------------------------

    @property
    def slave(self) -> int:
        """The slave number on the port this TES is reached on (``link``)."""
        return self.slave_for(self.link)

    def slave_for(self, link: Link) -> int:
        value = self.params[f"{state.link_key(link)}.slave"]
        assert isinstance(value, int)
        return value

    def answer_delay(self, link: Link) -> int:
        value = self.params[f"{state.link_key(link)}.answer_delay_ms"]
        assert isinstance(value, int)
        return value * MS

    def count(self, link: Link, counter: Counter, now: int) -> None:
        self.counters[state.link_key(link)].bump(counter)

    def advance(self, seconds_: float) -> None:
        self.clock.advance(seconds(seconds_))

    def read(self, address: int) -> int:
        """A master read of one word (memorized inputs are restored, §4.1.2)."""
        return self.get(self._register(address), self.clock.now)

    def peek_word(self, address: int) -> int:
        """The word as it stands, without a master read's side effects."""
        return self.peek(self._register(address), self.clock.now)

    def write(self, address: int, value: int) -> None:
        reg = self._register(address)
        if not reg.access.writable:
            raise ConfigError(f"{self.model.name} word {address:03X}h ({reg.name}) is read only")
        if not 0 <= value <= 0xFFFF:
            raise ConfigError(f"word value {value} out of range (allowed 0..65535)")
        self.put(reg, value, self.clock.now)

    def _register(self, address: int) -> Register:
        reg = self.registers.get(address)
        if reg is None:
            raise ConfigError(f"{self.model.name} has no word at address {address:03X}h")
        return reg

    def set_input(self, i: int, value: bool | float) -> None:
        """A digital input (bool) or an analog input (volts or milliamps)."""
        now = self.clock.now
        if isinstance(value, bool):
            self._drop_driver(i)
            self.di.set_contact(self._digital_index(i), value, now)
        else:
            self.ai.set_level(self._analog_index(i), float(value), now)

    def set_signal(
        self, i: int, signal: AnalogSource | DiscreteSource, digital: bool | None = None
    ) -> None:
        """Drive an input from a fieldtwin.signals signal (value_at / next_change)."""
        if digital is None:
            digital = not self.model.analog_inputs
        now = self.clock.now
        if digital:
            self._drop_driver(self._digital_index(i))
            source = cast(DiscreteSource, signal)
            driver = DiscreteDriver(self.clock, source, lambda v, t: self.di.set_contact(i, v, t))
            self._drivers[i] = driver
            driver.start(now)
        else:
            self.ai.set_signal(self._analog_index(i), signal, now)

    def _drop_driver(self, i: int) -> None:
        driver = self._drivers.pop(i, None)
        if driver is not None:
            driver.stop()

    def set_wiring(self, i: int, wiring: Wiring | str) -> None:
        """TES 32ET-S: a short circuit or a broken wire on input ``i`` (§4.1.5)."""
        if not self.model.safety:
            raise ConfigError(f"{self.model.name} has no safety inputs (only the TES 32ET-S)")
        try:
            w = Wiring(wiring)
        except ValueError:
            raise ConfigError(f"wiring {wiring!r} not allowed (allowed: ok, short, open)") from None
        self.di.set_wiring(self._digital_index(i), w, self.clock.now)
        if self.safety_default():
            self.status |= state.SAFETY  # §6.2.1 bit 2, reset by the master

    def _digital_index(self, i: int) -> int:
        if not 0 <= i < self.model.digital_inputs:
            raise ConfigError(
                f"{self.model.name}: no digital input {i}"
                f" (allowed 0..{self.model.digital_inputs - 1})"
            )
        return i

    def _analog_index(self, i: int) -> int:
        if i not in self.model.analog_inputs:
            allowed = ", ".join(map(str, self.model.analog_inputs)) or "none"
            raise ConfigError(f"{self.model.name}: no analog input {i} (allowed: {allowed})")
        return i

    def digital_output(self, i: int) -> bool:
        return self.do.state(i, self.clock.now)

    def analog_output(self, k: int) -> float:
        """Analog output k in volts or milliamps (§4.3.1)."""
        if k not in self.model.analog_outputs:
            raise ConfigError(f"{self.model.name}: no analog output {k}")
        points = dac_points(self.words.get(0x014 + k, 0), self.params, k)
        return points / 32767 * self.model.analog_range.full_scale

    @property
    def leds(self) -> dict[str, str]:
        """§3.1.2 front-panel LEDs."""
        on = "on" if self.powered else "off"
        return {
            "Pwr": on,
            "Run": on,
            "Prm": "on" if self.prm_jumper and self.powered else "off",
            "Wdg": "blinking" if self.wdg_blinking and self.powered else "off",
        }
