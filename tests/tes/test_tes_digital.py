"""§4.1 digital inputs and outputs, in simulated time."""

from __future__ import annotations

import pytest

from fieldtwin.modbus.model import Link
from fieldtwin.tes import Tes

from .helpers import pair, quick_status, read_word, read_words, write_word, write_words

MS = 0.001


def test_4_1_1_filter_confirms_after_5_ms_by_default() -> None:
    tes = Tes("TES 32EST")
    tes.set_input(0, True)
    tes.advance(4.9 * MS)
    assert read_word(tes, 0x005) == 1  # direct
    assert read_word(tes, 0x003) == 0  # filtered
    tes.advance(0.1 * MS)
    assert read_word(tes, 0x003) == 1


def test_4_1_1_separate_durations_for_state_0_and_1() -> None:
    tes = Tes("TES 32EST")
    write_word(tes, 0x00A, 20)  # state 0 confirmed after 100 ms
    write_word(tes, 0x00B, 2)  # state 1 confirmed after 10 ms
    tes.set_input(3, True)
    tes.advance(10 * MS)
    assert read_word(tes, 0x003) == 0x0008
    tes.set_input(3, False)
    tes.advance(99 * MS)
    assert read_word(tes, 0x003) == 0x0008
    tes.advance(1 * MS)
    assert read_word(tes, 0x003) == 0


def test_4_1_1_a_glitch_shorter_than_the_filter_is_ignored() -> None:
    tes = Tes("TES 16EST")
    tes.set_input(1, True)
    tes.advance(3 * MS)
    tes.set_input(1, False)
    tes.advance(1.0)
    assert read_word(tes, 0x003) == 0
    assert pair(tes, 0x027) == 0  # rising edges of input 1


def test_4_1_1_zero_filter_is_immediate() -> None:
    tes = Tes("TES 32ET")
    write_words(tes, 0x00A, (0, 0))
    tes.set_input(17, True)
    assert read_word(tes, 0x004) == 0x0002


def _toggle(tes: Tes, i: int, states: list[bool]) -> None:
    for s in states:
        tes.set_input(i, s)
        tes.advance(0.05)


def test_4_1_2_memorized_input_restores_one_change_per_read() -> None:
    tes = Tes("TES 32ET")
    _toggle(tes, 0, [True, False, True])
    assert quick_status(tes) == 0x09  # bit 0 power on, bit 3 changes pending
    # AMB-TES-12: each read shows the next change of the succession
    assert [read_word(tes, 0x001) & 1 for _ in range(4)] == [1, 0, 1, 1]
    assert quick_status(tes) == 0x01  # §6.2.1 bit 3 reset once all were read


def test_4_1_2_each_word_restores_only_its_inputs() -> None:
    tes = Tes("TES 32ET")
    _toggle(tes, 20, [True])
    assert read_word(tes, 0x001) == 0
    assert read_word(tes, 0x004) & (1 << 4)
    assert read_word(tes, 0x002) == 1 << 4
    assert read_words(tes, 0x001, 2) == (0, 1 << 4)


def test_4_1_3_rising_and_falling_counters_and_master_reset() -> None:
    tes = Tes("TES 32EST")
    _toggle(tes, 15, [True, False] * 3)
    assert pair(tes, 0x043) == 3  # §6.2.4.1 "TES 32 EST 043h/044h input No 15"
    assert pair(tes, 0x083) == 3  # §6.2.4.2 "083h/084h input No 15"
    assert write_words(tes, 0x043, (0, 0)) is None
    assert pair(tes, 0x043) == 0
    assert pair(tes, 0x083) == 3


def test_4_1_3_counters_are_32_bits() -> None:
    tes = Tes("TES 16EST")
    write_words(tes, 0x025, (0x0001, 0xFFFF))
    _toggle(tes, 0, [True])
    assert read_words(tes, 0x025, 2) == (0x0002, 0x0000)


def test_4_1_4_chronometers_of_last_and_running_states() -> None:
    tes = Tes("TES 32ET")
    tes.advance(2.5)
    assert pair(tes, 0x0E5) == 25  # state 0 in progress since power-on
    assert pair(tes, 0x165) == 25  # cumulated state 0
    tes.set_input(0, True)  # filtered at 2.505 s
    tes.advance(1.505)
    assert pair(tes, 0x0A5) == 15  # state 1 in progress
    assert pair(tes, 0x0E5) == 25  # last state 0
    tes.set_input(0, False)  # filtered at 4.010 s
    tes.advance(1.005)
    assert pair(tes, 0x0A5) == 15  # last state 1 (1.505 s)
    assert pair(tes, 0x0E5) == 10
    assert pair(tes, 0x165) == 35
    assert pair(tes, 0x125) == 15


def test_4_1_4_master_resets_cumulated_durations() -> None:
    tes = Tes("TES 32ET")
    tes.advance(3.0)
    write_words(tes, 0x165, (0, 0))
    tes.advance(0.5)
    assert pair(tes, 0x165) == 5
    assert pair(tes, 0x0E5) == 35  # the running state's duration is not touched


def test_6_2_6_cumulated_address_formula_for_input_x() -> None:
    tes = Tes("TES 32ET")
    tes.set_input(9, True)
    tes.advance(2.005)
    # §6.2.6.2 "for input No X a1 = 357 + 2 x": cumulated 0 of input 9 at 375
    assert pair(tes, 357 + 2 * 9) == 0
    assert pair(tes, 293 + 2 * 9) == 20


def test_4_1_6_blinking_at_frequency_a_and_b() -> None:
    tes = Tes("TES 32EST")
    write_word(tes, 0x00C, 0b011)  # outputs 0 and 1 blink
    write_word(tes, 0x00D, 0b110)  # output 0 frequency 0 (A), 1 frequency 1 (B), 2 fixed 1
    samples = []
    for t in (0.02, 0.07, 0.52, 1.02):
        tes.advance(t - tes.clock.now / 1e6)
        samples.append(read_word(tes, 0x007))
    # §3.1.2 factory: A = 1 Hz (500 ms on, 500 off), B = 10 Hz (50 / 50)
    assert samples == [0b111, 0b101, 0b110, 0b111]


def test_4_1_6_blink_durations_are_parameters() -> None:
    tes = Tes("TES 32ST")
    write_words(tes, 0x007, (2, 8))  # frequency 0: 10 ms on, 40 ms off
    write_words(tes, 0x003, (0xFFFF, 0xFFFF))
    states = []
    for _ in range(10):
        states.append(read_word(tes, 0x001) == 0xFFFF)
        tes.advance(0.005)
    assert states == [True, True, False, False, False, False, False, False, False, False]


def test_6_3_2_table_fixed_and_blinking_commands_of_32st() -> None:
    tes = Tes("TES 32ST")
    write_words(tes, 0x003, (0b1100, 0x0000))
    write_words(tes, 0x005, (0b1010, 0x8000))
    tes.advance(0.01)
    # output 0: command 0; 1: command 1; 2: freq 0 (on at 10 ms); 3: freq 1 (on)
    assert read_word(tes, 0x001) == 0b1110
    assert read_word(tes, 0x002) == 0x8000


def _silent_32est() -> Tes:
    tes = Tes("TES 32EST")
    write_word(tes, 0x016, 10)  # §6.2.3.1 watching time 1 s
    write_words(tes, 0x012, (0x0000, 0x0001, 0x0000, 0x00F0))  # OR 0, OR 1, AND 0, AND 1
    write_word(tes, 0x00D, 0x00FF)
    write_word(tes, 0x000, 0)  # master acknowledges the power-on bit
    return tes


def test_4_1_7_requests_keep_the_watchdog_from_firing() -> None:
    tes = _silent_32est()
    for _ in range(5):
        tes.advance(0.9)
        read_word(tes, 0x000)
    assert read_word(tes, 0x007) == 0x00FF
    assert tes.leds["Wdg"] == "off"


def test_4_1_7_silence_puts_outputs_in_fallback_and_recovery() -> None:
    tes = _silent_32est()
    tes.advance(0.999)
    assert tes.peek_word(0x007) == 0x00FF
    tes.advance(0.001)
    # AMB-TES-11 (command AND mask) OR mask: outputs 4..7 unchanged, 0 forced on, 1..3 off
    assert tes.peek_word(0x007) == 0x00F1
    assert tes.leds["Wdg"] == "blink"
    assert quick_status(tes) == 0x02  # bit 1 set by TES
    assert tes.leds["Wdg"] == "off"  # the master is back
    write_word(tes, 0x00D, 0x000F)
    write_word(tes, 0x000, 0)  # bit 1 reset by master
    assert read_word(tes, 0x007) == 0x000F
    assert quick_status(tes) == 0


def test_4_1_7_fallback_stops_blinking_when_the_and_mask_clears_it() -> None:
    tes = _silent_32est()
    write_word(tes, 0x00C, 0x0001)  # output 0 blinks
    tes.advance(1.0)
    assert tes.peek_word(0x00C) == 0  # AND mask of word 0 is 0: fixed


def test_amb_tes_10_rs232_requests_do_not_rearm_the_watchdog() -> None:
    tes = _silent_32est()
    tes.advance(0.5)
    read_words(tes, 0x000, 1, link=Link.RS232)
    tes.advance(0.5)
    assert tes.peek_word(0x000) & 0x02


def test_watchdog_zero_never_falls_back() -> None:
    tes = Tes("TES 32EST")
    write_word(tes, 0x00D, 0x0003)
    tes.advance(3600.0)
    assert read_word(tes, 0x007) == 0x0003
    assert tes.clock.next_deadline() is None  # an idle TES schedules nothing


def test_6_3_1_32st_fallback_with_32_bit_masks() -> None:
    tes = Tes("TES 32ST")
    write_word(tes, 0x016, 5)
    write_words(tes, 0x005, (0xFFFF, 0xFFFF))
    # OR word 1 high half: force output 31 on; AND word 1: keep outputs 0..7
    write_words(tes, 0x00E, (0, 0, 0, 0x8000, 0, 0, 0x00FF, 0))
    tes.advance(0.5)
    assert tes.peek_word(0x001) == 0x00FF
    assert tes.peek_word(0x002) == 0x8000
    assert tes.peek_word(0x000) & 0x02


def test_6_2_1_status_bits_reset_by_master_and_bit_3_by_tes() -> None:
    tes = Tes("TES 32ET")
    _toggle(tes, 0, [True])
    assert read_word(tes, 0x000) == 0x09
    write_word(tes, 0x000, 0)
    assert read_word(tes, 0x000) == 0x08  # bit 3 stays while changes wait
    read_word(tes, 0x001)
    assert read_word(tes, 0x000) == 0


@pytest.mark.parametrize(("i", "word", "bit"), [(0, 0, 0), (15, 0, 15), (16, 1, 0), (31, 1, 15)])
def test_6_2_7_short_and_open_circuits_on_32et_s(i: int, word: int, bit: int) -> None:
    tes = Tes("TES 32ET-S")
    write_words(tes, 0x1AB, (0xFFFF, 0xFFFF))  # all inputs wired in security mode
    write_word(tes, 0x000, 0)
    tes.set_wiring(i, "short")
    tes.advance(0.01)
    assert read_word(tes, 0x1A5 + word) == 1 << bit  # AMB-TES-23: bit 0 = E1
    assert read_word(tes, 0x1A9 + word) == 1 << bit
    assert read_word(tes, 0x003 + word) == 1 << bit  # a short looks closed
    assert quick_status(tes) == 0x04 | 0x08
    tes.set_wiring(i, "open")
    assert read_word(tes, 0x1A7 + word) == 1 << bit
    assert read_word(tes, 0x1A5 + word) == 0
    tes.set_wiring(i, "ok")
    assert read_word(tes, 0x1A9 + word) == 0
    assert read_word(tes, 0x000) & 0x04  # latched until the master resets it


def test_4_1_5_a_safety_input_used_as_a_normal_input_reports_nothing() -> None:
    tes = Tes("TES 32ET-S")
    write_word(tes, 0x1AB, 0x0001)
    write_word(tes, 0x000, 0)
    tes.set_wiring(1, "open")
    assert read_words(tes, 0x1A5, 6) == (0, 0, 0, 0, 0, 0)
    assert read_word(tes, 0x000) & 0x04 == 0


def test_digital_signal_drives_an_input() -> None:
    from fieldtwin.signals import PulseTrain

    tes = Tes("TES 32ET")
    pulses = PulseTrain(period_us=100_000, duty=0.2)
    tes.set_signal(2, pulses)
    tes.advance(1.0)
    assert pair(tes, 0x029) == 10
    assert pair(tes, 0x069) in (9, 10)


def test_power_cycle_clears_ram_and_reloads_mp_words() -> None:
    tes = Tes("TES 32EST")
    _toggle(tes, 0, [True, False])
    write_word(tes, 0x00A, 40)  # on-line change of the filter
    write_word(tes, 0x000, 0)
    tes.power_cycle()
    assert read_word(tes, 0x00A) == 1  # §1 back to the EEPROM value (5 ms)
    assert pair(tes, 0x025) == 0
    assert read_word(tes, 0x000) == 0x01  # bit 0: powered on again
