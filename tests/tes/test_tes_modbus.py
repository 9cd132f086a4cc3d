"""§7 Modbus semantics on the device side: functions, bit addressing, broadcast, exceptions."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.modbus.model import (
    NO_REPLY,
    Counter,
    ExceptionCode,
    Link,
    ReadBits,
    ReadWords,
    WriteBit,
    WriteWord,
    WriteWords,
)
from fieldtwin.tes import Tes
from fieldtwin.tes.state import LineFault

from .helpers import read_bits, read_word, read_words, write_bit, write_bits, write_word


def test_7_1_2_bit_address_is_word_times_16_plus_bit() -> None:
    tes = Tes("TES 32EST")
    write_word(tes, 0x00D, 0x2000)
    # §7.1.2 "address of bit D in word 7A is 7AD": here bit D of word 00D
    assert read_bits(tes, 0x00DD, 1) == (True,)
    assert read_bits(tes, 0x00DC, 3, function=2) == (False, True, False)


def test_7_2_4_bits_across_words() -> None:
    tes = Tes("TES 32ST")
    write_word(tes, 0x005, 0x8000)
    write_word(tes, 0x006, 0x0001)
    assert read_bits(tes, 0x005F, 2) == (True, True)


def test_fc05_and_fc0f_write_bits_in_words() -> None:
    tes = Tes("TES 32ST")
    assert write_bit(tes, 0x0053, True) is None
    assert read_word(tes, 0x005) == 0x0008
    assert write_bits(tes, 0x005E, (True, True, True)) is None
    assert read_words(tes, 0x005, 2) == (0xC008, 0x0001)
    assert write_bit(tes, 0x0053, False) is None
    assert read_word(tes, 0x005) == 0xC000


def test_fc04_reads_the_same_memory_as_fc03() -> None:
    tes = Tes("TES 8EA")
    write_word(tes, 0x055, 7)
    assert tes.execute(ReadWords(4, 0x055, 1), Link.RS485, 0, False) == (7,)


def test_exception_1_for_a_function_the_request_type_does_not_carry() -> None:
    tes = Tes("TES 8EA")
    assert tes.execute(ReadWords(5, 0, 1), Link.RS485, 0, False) is ExceptionCode.ILLEGAL_FUNCTION
    assert tes.execute(ReadBits(3, 0, 1), Link.RS485, 0, False) is ExceptionCode.ILLEGAL_FUNCTION


def test_exception_2_for_bad_addresses_and_quantities() -> None:
    tes = Tes("TES 32ST")
    bad = ExceptionCode.ILLEGAL_DATA_ADDRESS
    assert read_words(tes, 0x025) is bad
    assert read_words(tes, 0x000, 0) is bad
    assert read_words(tes, 0x000, 126) is bad
    assert write_word(tes, 0x001, 1) is bad  # outputs state is read only
    assert read_bits(tes, 0x0240, 17) is bad  # runs into word 025h
    assert tes.execute(WriteWords(0x005, ()), Link.RS485, 0, False) is bad


def test_exception_4_not_ready_in_the_32_bit_area_only() -> None:
    tes = Tes("TES 32ET")
    tes.inject_not_ready(1)
    assert isinstance(read_words(tes, 0x000, 0x25), tuple)  # below 025h: never refused
    assert read_words(tes, 0x025, 2) is ExceptionCode.SLAVE_DEVICE_FAILURE
    assert isinstance(read_words(tes, 0x025, 2), tuple)


def test_not_ready_window_after_each_buffer_refresh() -> None:
    tes = Tes("TES 8EA")
    tes.not_ready_window_us = 2_000
    tes.advance(0.1005)
    assert read_words(tes, 0x41F, 2) is ExceptionCode.SLAVE_DEVICE_FAILURE
    tes.advance(0.002)
    assert isinstance(read_words(tes, 0x41F, 2), tuple)


def test_counters_per_link_and_not_ready_counted_apart() -> None:
    tes = Tes("TES 32ET")
    tes.count(Link.RS485, Counter.GOOD_FRAMES, 0)
    tes.count(Link.RS485, Counter.FRAMES_EXECUTED, 0)
    tes.count(Link.RS232, Counter.CRC_ERRORS, 0)
    tes.count(Link.RS485, Counter.EXCEPTION_REPLIES, 0)
    tes.inject_not_ready()
    read_words(tes, 0x030)
    tes.count(Link.RS485, Counter.EXCEPTION_REPLIES, 0)  # the core counts the refusal
    assert read_words(tes, 0x017, 7) == (1, 1, 1, 0, 0, 1, 0)
    assert read_words(tes, 0x01E, 7) == (0, 0, 0, 1, 0, 0, 0)


def test_6_4_12_counters_of_analog_tes_and_tcp_counts_as_rs485() -> None:
    tes = Tes("TES 4SA")
    tes.count(Link.TCP, Counter.NO_SILENCE, 0)
    tes.count(Link.RS232, Counter.WRONG_CHARACTERS, 0)
    assert read_word(tes, 0x04D) == 1
    assert read_word(tes, 0x052) == 1


def test_7_2_6_broadcast_writes_run_without_reply_reads_are_ignored() -> None:
    tes = Tes("TES 32ST")
    assert tes.execute(WriteWord(0x005, 0x00FF), Link.RS485, 0, True) is None
    assert read_word(tes, 0x001) == 0x00FF
    assert tes.execute(ReadWords(3, 0x000, 1), Link.RS485, 0, True) is None
    assert tes.execute(WriteBit(0x0050, False), Link.RS485, 0, True) is None
    assert read_word(tes, 0x005) == 0x00FE


def test_a_tes_without_power_does_not_answer() -> None:
    tes = Tes("TES 32ST")
    tes.power_off()
    assert read_words(tes, 0x000) is NO_REPLY
    assert tes.leds["Pwr"] == "off"
    tes.power_on()
    assert read_words(tes, 0x000) == (1,)


def test_answer_delay_per_link() -> None:
    tes = Tes("TES 32ET")
    tes.write_eeprom({"rs485.answer_delay_ms": 20, "rs232.answer_delay_ms": 3})
    tes.power_cycle()
    assert tes.answer_delay(Link.RS485) == 20_000
    assert tes.answer_delay(Link.TCP) == 20_000
    assert tes.answer_delay(Link.RS232) == 3_000


def test_line_faults_are_handed_to_the_line_glue_once_each() -> None:
    tes = Tes("TES 32ET")
    tes.inject_line_fault("bad_crc", 2)
    tes.inject_line_fault(LineFault.BROKEN_CHARACTER, 1, Link.RS232)
    assert tes.take_line_fault(Link.RS485) is LineFault.BAD_CRC
    assert tes.take_line_fault(Link.TCP) is LineFault.BAD_CRC
    assert tes.take_line_fault(Link.RS485) is None
    assert tes.take_line_fault(Link.RS232) is LineFault.BROKEN_CHARACTER


_TES = {name: Tes(name) for name in ("TES 32ET-S", "TES 32ST", "TES 8ESA")}


@settings(max_examples=300, deadline=None)
@given(
    st.sampled_from(sorted(_TES)),
    st.integers(1, 4),
    st.integers(0, 0x500),
    st.integers(0, 130),
)
def test_any_read_gives_words_or_an_exception(name: str, fc: int, address: int, count: int) -> None:
    tes = _TES[name]
    request = ReadWords(fc, address, count) if fc >= 3 else ReadBits(fc, address, count)
    result = tes.execute(request, Link.RS485, tes.clock.now, False)
    assert isinstance(result, ExceptionCode) or (isinstance(result, tuple) and len(result) == count)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 0x60), st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=8))
def test_any_write_succeeds_or_gives_exception_2(address: int, values: list[int]) -> None:
    tes = _TES["TES 32ST"]
    result = tes.execute(WriteWords(address, tuple(values)), Link.RS485, tes.clock.now, False)
    assert result is None or result is ExceptionCode.ILLEGAL_DATA_ADDRESS
