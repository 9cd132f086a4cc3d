"""The public Python API of a TES: seconds, LEDs, read vs peek, input names, ranges."""

from __future__ import annotations

import math

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.signals import Constant
from fieldtwin.tes import Tes
from fieldtwin.tes.inputs import parse_bool

from .helpers import read_word


def test_simulated_time_in_seconds() -> None:
    tes = Tes("TES 32EST")
    assert tes.now_s == 0.0
    tes.advance(0.25)
    tes.advance_to(1.5)
    assert tes.now_s == 1.5 and tes.clock.now == 1_500_000
    with pytest.raises(ConfigError, match="time never goes back"):
        tes.advance_to(1.0)


def test_leds_are_on_off_or_blink() -> None:
    tes = Tes("TES 32EST", prm_jumper=True)
    assert tes.leds == {"Pwr": "on", "Run": "on", "Prm": "on", "Wdg": "off"}
    tes.write(0x016, 10)  # watchdog 1 s
    tes.advance(1.0)
    assert tes.leds["Wdg"] == "blink"  # §3.1.3 "led Wdg will blinking"
    assert set(tes.leds.values()) <= {"on", "off", "blink"}
    tes.read(0x000)  # a master read is a request: the master is back
    assert tes.leds["Wdg"] == "off"


def test_read_clears_the_8ea_status_bits_as_on_the_wire_peek_does_not() -> None:
    """Issue 10 item 19: one rule for every model."""
    tes = Tes("TES 8EA")
    assert tes.peek(0x000) & 0x01 and tes.peek(0x000) & 0x01  # peek: no side effect
    assert tes.read(0x000) & 0x01  # the reply still shows bit 0 ...
    assert tes.peek(0x000) & 0x01 == 0  # ... the exchange clears it (§6.4.1)
    wire = Tes("TES 8EA")
    read_word(wire, 0x000)
    assert wire.peek(0x000) == tes.peek(0x000)


def test_read_consumes_memorized_changes_peek_does_not() -> None:
    tes = Tes("TES 32EST")
    tes.set_input(2, True)
    tes.advance(0.1)
    tes.set_input(2, False)
    tes.advance(0.1)
    assert tes.peek(0x001) == 0 and tes.peek(0x001) == 0  # §4.1.2 nothing restored by peek
    assert tes.read(0x001) == 1 << 2  # first change restored
    assert tes.read(0x001) == 0  # second change restored
    assert tes.peek(0x000) & 0x08 == 0  # §6.2.1 bit 3: all read


def test_read_and_write_of_an_unpowered_tes_get_no_answer() -> None:
    tes = Tes("TES 32ST")
    tes.power_off()
    with pytest.raises(ConfigError, match="powered off, a master gets no answer"):
        tes.read(0x000)
    with pytest.raises(ConfigError, match="powered off"):
        tes.write(0x005, 1)
    assert tes.peek(0x000) == 0x01  # peek still shows the word


def test_inputs_by_name() -> None:
    tes = Tes("TES 8ESA")
    assert list(tes.input_names()) == ["0", "1", "2", "3", "a0", "a1", "a2", "a3"]
    tes.set_input("a1", 5.0)
    tes.set_input("2", "on")
    tes.set_input("3", 1)
    tes.advance(0.2)
    assert tes.peek(0x004) == 512 and tes.peek(0x001) == 0b1100
    with pytest.raises(ConfigError, match=r"no analog input 5 \(allowed: 0, 1, 2, 3\)"):
        tes.set_input("a5", 1.0)
    with pytest.raises(ConfigError, match=r"input 2: 'maybe' is not on or off"):
        tes.set_input("2", "maybe")
    with pytest.raises(ConfigError, match=r"input 2: 2 is not on or off"):
        tes.set_input("2", 2)


@pytest.mark.parametrize(("level", "points"), [(15.0, 1023), (-5.0, 0), (1e308, 1023)])
def test_4_2_4_a_level_beyond_the_converter_saturates_and_says_so(
    level: float, points: int
) -> None:
    """Issue 10 item 13: saturate as the converter would, and say so."""
    tes = Tes("TES 8EA")
    note = tes.set_input(0, level)
    assert note is not None
    assert f"{level:g} V is outside the converter's 0..10 V" in note
    assert f"reads as {points} points" in note
    tes.advance(1.0)
    assert tes.peek(0x003) == points
    assert tes.set_input(0, 10.0) is None and tes.set_input(0, 0.0) is None


def test_a_constant_signal_beyond_the_span_gets_the_same_note() -> None:
    tes = Tes("TES 4EA")
    note = tes.set_signal(1, Constant(25.0), digital=False)
    assert note is not None and "saturated" in note
    assert tes.set_signal(1, Constant(2.0), digital=False) is None


def test_a_level_that_is_not_a_finite_number_is_refused() -> None:
    tes = Tes("TES 8EA")
    with pytest.raises(ConfigError, match="a0: nan is not a finite number"):
        tes.set_input(0, math.nan)
    with pytest.raises(ConfigError, match="a0: 'high' is not a number"):
        tes.set_input("a0", "high")


@pytest.mark.parametrize("word", ["on", "ON", "1", "true", "Yes"])
def test_boolean_words_on(word: str) -> None:
    assert parse_bool(word, "x") is True


@pytest.mark.parametrize("word", ["off", "0", "False", "no"])
def test_boolean_words_off(word: str) -> None:
    assert parse_bool(word, "x") is False


@pytest.mark.parametrize("word", ["maybe", "banana", "2", ""])
def test_other_words_are_refused_naming_the_token(word: str) -> None:
    with pytest.raises(ConfigError, match=f"x: {word!r} is not on or off"):
        parse_bool(word, "x")


def test_words_by_address_or_by_name() -> None:
    tes = Tes("TES 8EA")
    tes.set_input("a3", 10.0)
    tes.advance(1.0)
    assert tes.peek("analog_input[3]") == tes.peek(0x006) == 1023
    assert tes.register("rs485.crc_errors").address == 0x04A
    tes.write("low_threshold[0]", 5)
    assert tes.read(0x023) == 5
    with pytest.raises(ConfigError, match=r"no word named 'colour'"):
        tes.read("colour")
    with pytest.raises(ConfigError, match=r"word 003h \(analog_input\[0\]\) is read only"):
        tes.write("analog_input[0]", 1)
