"""TESIS "I/O Test" (§5): set inputs, force outputs, show every input and output."""

from __future__ import annotations

import math

from rich.table import Table

from fieldtwin.errors import ConfigError
from fieldtwin.tes.inputs import input_ref, parse_bool
from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import Family
from fieldtwin.words import to_signed


def _split(item: str, what: str) -> tuple[str, str]:
    name, sep, value = item.partition("=")
    if not sep or not name or not value:
        raise ConfigError(f"iotest --{what} {item!r}: expected I=V (3=1 digital, a2=4.5 analog)")
    return name.strip().lower(), value.strip()


def _number(text: str, item: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"iotest {item!r}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"iotest {item!r}: {text!r} is not a finite number")
    return value


def _index(text: str, item: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ConfigError(f"iotest {item!r}: {text!r} is not a channel number") from None


def apply_forces(tes: Tes, inputs: list[str], outputs: list[str]) -> list[str]:
    """Apply ``I=V`` inputs and outputs; the notes of inputs that saturate (§4.2.4)."""
    notes = []
    for item in inputs:
        name, value = _split(item, "input")
        if name.startswith("a"):
            note = tes.set_input(input_ref(tes.model, name).name, _number(value, item))
        else:
            ref = input_ref(tes.model, name)
            note = tes.set_input(ref.name, parse_bool(value, f"iotest --input {item!r}"))
        if note is not None:
            notes.append(note)
    for item in outputs:
        name, value = _split(item, "output")
        if name.startswith("a"):
            k = _index(name[1:], item)
            if k not in tes.model.analog_outputs:
                raise ConfigError(f"iotest {item!r}: {tes.model.name} has no analog output {k}")
            tes.write(0x014 + k, round(_number(value, item)) & 0xFFFF)
        else:
            on = parse_bool(value, f"iotest --output {item!r}")
            force_digital(tes, _index(name, item), on)
    return notes


def force_digital(tes: Tes, i: int, on: bool) -> None:
    """Set output ``i`` fixed on or off through its command word (§6.2.2, 6.3.2, 6.4.5)."""
    if not 0 <= i < tes.model.digital_outputs:
        raise ConfigError(
            f"{tes.model.name}: no digital output {i} (allowed 0..{tes.model.digital_outputs - 1})"
        )
    family = tes.model.family
    if family is Family.ANALOG:
        address, bit, select = 0x013, i, 0x013
    elif family is Family.DIGITAL_OUTPUTS:
        address, bit, select = 0x005 + i // 16, i % 16, 0x003 + i // 16
    else:
        address, bit, select = 0x00D, i, 0x00C
    select_bit = bit + 8 if family is Family.ANALOG else bit
    tes.write(select, tes.peek(select) & ~(1 << select_bit) & 0xFFFF)
    word = tes.peek(address)
    tes.write(address, (word | (1 << bit)) if on else (word & ~(1 << bit) & 0xFFFF))


def _onoff(value: bool) -> str:
    return "1" if value else "0"


def io_tables(tes: Tes) -> list[Table]:
    m, now = tes.model, tes.clock.now
    tables = []
    if m.digital_inputs:
        t = Table("input", "direct", "filtered", title=f"{m.name} digital inputs")
        for i in range(m.digital_inputs):
            t.add_row(str(i), _onoff(tes.di.direct(i)), _onoff(tes.di.filtered(i)))
        tables.append(t)
    if m.digital_outputs:
        t = Table("output", "state", title=f"{m.name} digital outputs")
        for i in range(m.digital_outputs):
            t.add_row(str(i), _onoff(tes.do.state(i, now)))
        tables.append(t)
    unit = m.analog_range.unit
    if m.analog_inputs:
        t = Table("input", f"level ({unit})", "value", "state", title=f"{m.name} analog inputs")
        for k in m.analog_inputs:
            level = tes.ai.level(k, now)
            value = to_signed(tes.peek(0x003 + k))
            t.add_row(f"a{k}", f"{level:.3f}", str(value), f"{tes.peek(0x00B + k):04X}")
        tables.append(t)
    if m.analog_outputs:
        t = Table("output", "word", f"level ({unit})", title=f"{m.name} analog outputs")
        for k in m.analog_outputs:
            word = to_signed(tes.peek(0x014 + k))
            t.add_row(f"a{k}", str(word), f"{tes.analog_output(k):.3f}")
        tables.append(t)
    return tables
