"""§4.2 analog inputs and §4.3 analog outputs, in simulated time."""

from __future__ import annotations

import pytest

from fieldtwin.signals import Ramp, Sine
from fieldtwin.tes import Tes
from fieldtwin.tes.params import Value

from .helpers import quick_status, read_word, write_word, write_words

MS = 0.001


def _configured(model: str, **values: Value) -> Tes:
    tes = Tes(model)
    tes.write_eeprom({k.replace("__", "."): v for k, v in values.items()})
    tes.power_cycle()
    return tes


def _at(tes: Tes, seconds: float) -> None:
    tes.clock.run_until(round(seconds * 1_000_000))


@pytest.mark.parametrize(
    ("model", "period_ms"), [("TES 4EA", 32), ("TES 8EA", 64), ("TES 8ESA", 32)]
)
def test_4_2_1_one_channel_every_8_ms_in_turn(model: str, period_ms: int) -> None:
    tes = Tes(model)
    tes.set_input(1, 10.0)
    _at(tes, 15.9 * MS)
    assert read_word(tes, 0x004) == 0
    _at(tes, 16 * MS)  # channel 1 is the second of the round
    assert read_word(tes, 0x004) == 1023
    tes.set_input(1, 0.0)
    _at(tes, (16 + period_ms) * MS - 1e-6)
    assert read_word(tes, 0x004) == 1023
    _at(tes, (16 + period_ms) * MS)
    assert read_word(tes, 0x004) == 512  # §4.2.3 N = 2: (1023 + 0) / 2, rounded


def test_4_2_3_average_on_the_last_n_samples() -> None:
    tes = _configured("TES 4EA", ai0__filter=4)
    tes.advance(1.01)  # between two acquisitions of channel 0 (8 ms + k x 32 ms)
    tes.set_input(0, 10.0)
    seen = []
    for _ in range(5):
        tes.advance(0.032)
        seen.append(read_word(tes, 0x003))
    assert seen == [256, 512, 767, 1023, 1023]


def test_amb_tes_16_average_of_the_samples_available_at_start() -> None:
    tes = _configured("TES 4EA", ai0__filter=256)
    tes.set_input(0, 10.0)
    _at(tes, 8 * MS)
    assert read_word(tes, 0x003) == 1023


def test_4_2_4_points_without_scaling() -> None:
    tes = Tes("TES 8EA")
    for k, volts in enumerate((0.0, 2.5, 5.0, 10.0, 12.0)):
        tes.set_input(k, volts)
    tes.advance(1.0)
    assert [read_word(tes, 0x003 + k) for k in range(5)] == [0, 256, 512, 1023, 1023]


def test_4_2_4_scaling_example_minus_100_to_15000() -> None:
    tes = _configured("TES 8EA", ai0__scale="on", ai0__scale_min=-100, ai0__scale_max=15000)
    for volts, expected in ((0.0, 0xFF9C), (10.0, 15000), (5.0, 7457)):
        tes.set_input(0, volts)
        tes.advance(1.0)
        assert read_word(tes, 0x003) == expected


def test_4_2_5_corrections_in_points() -> None:
    tes = _configured("TES 4EA", ai0__corr_zero=5, ai0__corr_full=-5)
    tes.advance(1.0)
    assert read_word(tes, 0x003) == 5
    tes.set_input(0, 10.0)
    tes.advance(1.0)
    assert read_word(tes, 0x003) == 1018


def _thresholds(kind: str, **extra: Value) -> Tes:
    return _configured("TES 8EA", ai2__threshold=kind, ai2__low=300, ai2__high=700, **extra)


def test_4_2_6_1_simple_thresholds_set_bits_4_and_5() -> None:
    tes = _thresholds("simple")
    tes.set_input(2, 5.0)
    tes.advance(1.0)
    write_word(tes, 0x000, 0)
    assert read_word(tes, 0x00D) == 0
    tes.set_input(2, 1.0)
    tes.advance(1.0)
    assert read_word(tes, 0x00D) == 0x10  # input < low threshold
    assert read_word(tes, 0x000) & 0xC0 == 0x40
    tes.set_input(2, 9.0)
    tes.advance(1.0)
    assert read_word(tes, 0x00D) == 0x20
    assert read_word(tes, 0x013) == 0 and tes.peek_word(0x01C) >> 8 == 0  # no output
    tes.set_input(2, 5.0)
    tes.advance(1.0)
    assert read_word(tes, 0x00D) == 0  # AMB-TES-19 channel bits are live...
    assert read_word(tes, 0x000) & 0xC0 == 0xC0  # ... the summary bits latched
    write_word(tes, 0x000, 0)
    assert read_word(tes, 0x000) & 0xC0 == 0


def test_4_2_6_2_hysteresis_reflex_output() -> None:
    tes = _thresholds("hysteresis", ai2__out_high=2)
    states = []
    for volts in (5.0, 8.0, 5.0, 1.0, 5.0):
        tes.set_input(2, volts)
        tes.advance(1.0)
        states.append(tes.digital_output(2))
    assert states == [False, True, True, False, False]


def test_4_2_6_2_reversed_polarity() -> None:
    tes = _thresholds("hysteresis", ai2__out_high=2, threshold_polarity=0b0100)
    tes.set_input(2, 8.0)
    tes.advance(1.0)
    assert tes.digital_output(2) is False
    assert read_word(tes, 0x01C) & 0x0F00 == 0  # §6.4.7 direct outputs in bits 8..B
    tes.set_input(2, 1.0)
    tes.advance(1.0)
    assert read_word(tes, 0x01C) & 0x0F00 == 0x0400


def test_4_2_6_3_high_and_low_outputs_follow_their_conditions() -> None:
    tes = _thresholds("high_low", ai2__out_high=0, ai2__out_low=1)
    result = []
    for volts in (1.0, 5.0, 9.0):
        tes.set_input(2, volts)
        tes.advance(1.0)
        result.append((tes.digital_output(0), tes.digital_output(1)))
    assert result == [(False, True), (False, False), (True, False)]


def test_6_4_5_master_cannot_command_a_threshold_output() -> None:
    tes = _thresholds("high_low", ai2__out_high=0, ai2__out_low=1)
    tes.set_input(2, 5.0)
    tes.advance(1.0)
    write_word(tes, 0x013, 0x000F)
    assert [tes.digital_output(i) for i in range(4)] == [False, False, True, True]


def test_6_4_8_online_threshold_change_applies_at_once() -> None:
    tes = _thresholds("simple")
    tes.set_input(2, 5.0)
    tes.advance(1.0)
    write_word(tes, 0x02D, 100)  # high threshold of input 2
    assert read_word(tes, 0x00D) == 0x20


def test_4_2_2_history_of_120_values_newest_first() -> None:
    tes = Tes("TES 4EA")  # storage period 1 s
    for volts in (1.0, 2.0, 3.0):
        tes.set_input(3, volts)
        tes.advance(1.0)
    start = 450  # §6.4.13 input No 3
    assert [read_word(tes, start + j) for j in range(4)] == [307, 205, 102, 0]
    tes.advance(200.0)
    assert read_word(tes, start + 119) == 307
    assert read_word(tes, start + 120) == 0  # reserved


def test_6_4_13_storage_period_is_a_register() -> None:
    tes = Tes("TES 4EA")
    write_word(tes, 0x055, 5)
    tes.set_input(0, 5.0)
    tes.advance(4.9)
    assert read_word(tes, 87) == 0
    tes.advance(0.2)
    assert read_word(tes, 87) == 512


def test_a_settled_analog_tes_schedules_nothing() -> None:
    tes = Tes("TES 8EA")
    write_word(tes, 0x055, 0)  # no storage
    tes.set_input(0, 3.0)
    tes.advance(1.0)
    assert tes.clock.next_deadline() is None
    tes.set_input(0, 4.0)
    assert tes.clock.next_deadline() is not None


def test_analog_signals_are_sampled_at_acquisition_times() -> None:
    tes = Tes("TES 4EA")
    tes.set_signal(0, Ramp(0.0, 10.0, 0, 1_000_000))
    tes.set_signal(1, Sine(5.0, 5.0, 1_000_000))
    tes.advance(2.0)
    assert read_word(tes, 0x003) == 1023
    values = set()
    for _ in range(10):
        tes.advance(0.1)
        values.add(read_word(tes, 0x004))
    assert len(values) > 5


def test_6_4_1_analog_status_bits_0_1_reset_at_first_exchange() -> None:
    tes = Tes("TES 8EA")
    assert quick_status(tes) == 0x01
    assert quick_status(tes) == 0x00


def test_4_3_1_analog_output_without_scaling() -> None:
    tes = Tes("TES 4SA")
    write_word(tes, 0x015, 16384)
    assert tes.analog_output(1) == pytest.approx(5.0, abs=1e-3)
    write_word(tes, 0x015, 0xFFFF)  # negative: the converter stops at 0
    assert tes.analog_output(1) == 0.0


def test_4_3_1_analog_output_scaling() -> None:
    tes = _configured("TES 8SA-U", ao7__scale="on", ao7__scale_min=-1000, ao7__scale_max=1000)
    write_word(tes, 0x01B, 0)
    assert tes.analog_output(7) == pytest.approx(5.0, abs=1e-3)
    write_word(tes, 0x01B, 1000)
    assert tes.analog_output(7) == pytest.approx(10.0)


def test_4_3_2_fallback_values_for_authorised_outputs_only() -> None:
    tes = _configured(
        "TES 8ESA",
        watchdog_100ms=10,
        ao5__fallback=1234,
        ao__fallback_enable=0b0010_0000,
        fallback__digital_command=0x0003,
    )
    write_words(tes, 0x018, (100, 200))  # outputs No 4 and 5 (§6.4.6 warning)
    write_word(tes, 0x013, 0x0000)
    tes.advance(1.0)
    assert (read_word(tes, 0x018), read_word(tes, 0x019)) == (100, 1234)
    assert read_word(tes, 0x010) == 0x02  # channel No 5 in fallback
    assert read_word(tes, 0x00F) == 0
    assert read_word(tes, 0x013) == 0x0003  # §6.4.11.2 fallback command word
    write_word(tes, 0x019, 300)
    assert read_word(tes, 0x010) == 0


def test_6_4_11_threshold_outputs_do_not_fall_back() -> None:
    tes = _thresholds("high_low", ai2__out_high=0, ai2__out_low=1, watchdog_100ms=5)
    tes.set_input(2, 9.0)
    write_word(tes, 0x03D, 0x0000)
    tes.advance(1.0)
    assert tes.digital_output(0) is True
