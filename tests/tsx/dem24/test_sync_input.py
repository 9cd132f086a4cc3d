"""The synchronization input IN-SYN and its electrical timing (DEM 1.2-1, 7.2)."""

from __future__ import annotations

import pytest

from fieldtwin.clock import MS, S
from fieldtwin.errors import ConfigError
from fieldtwin.signals import PulseTrain
from fieldtwin.tsx.dem24.syncinput import SYNC_FILTER_US, SYNC_PULSE_US, SyncLevel
from tests.tsx.dem24.helpers import SLOT, at, make, read_all, stamp, synced


def test_1_2_1_a_pulse_shorter_than_the_500_us_filter_is_ignored() -> None:
    # DEM 1.2-1 "The synchronization input is filtered at 500 microseconds"
    plc, mod = make()
    mod.sync_pulse(width_us=499)
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},7") == 0 and mod.timebase.pulses == 0
    assert mod.sync_input.ignored == 1 and mod.sync_input.taken == 0
    mod.sync_pulse(width_us=500)  # held for the whole filter: counted
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},7") == 1 and mod.timebase.pulses == 1


def test_7_2_a_pulse_is_taken_at_the_end_of_the_filter_and_refers_to_its_leading_edge() -> None:
    plc, mod = make()
    edge = plc.clock.now
    mod.sync_pulse()
    plc.clock.run_until(edge + SYNC_FILTER_US - 1)
    assert not mod.pulse_image and mod.sync_input.state is SyncLevel.FILTERING
    plc.clock.run_until(edge + SYNC_FILTER_US)
    assert mod.pulse_image and mod.sync_input.state is SyncLevel.HELD
    assert mod.timebase.last_pulse_us == edge  # the leading edge marks the pulse
    plc.clock.run_until(edge + SYNC_PULSE_US)
    assert mod.sync_input.state is SyncLevel.REST


def test_7_2_the_time_is_taken_at_the_leading_edge_of_a_filtered_pulse() -> None:
    plc, mod = synced()  # 18:06:00.000 taken at the pulse whose leading edge is at 71 s
    assert str(mod.timebase.now(71 * S)).startswith("1994-07-15 18:06:00.000")


def test_7_2_too_short_pulses_from_the_source_are_a_loss_of_synchronization() -> None:
    # the source keeps its period but its pulses no longer pass the filter
    plc, mod = synced()
    mod.attach_pulse_source(60 * S, 131 * S, width_us=400)
    at(plc, 131.002)
    assert plc.read(f"I{SLOT},4") == 0  # T-SYN + DRIFT (+ the filter) not yet over
    at(plc, 131.01)
    assert plc.read(f"I{SLOT},4") == 1 and mod.sync_input.ignored == 1
    (msg,) = read_all(plc)
    assert msg[7] == (24 << 8) | 1 and stamp(msg) == (94, 7, 15, 18, 7, 0, 2)


def test_7_2_a_pulse_longer_than_10_ms_counts_once() -> None:
    # "the synchronization pulse time is less than 10 ms" is what the emitter gives;
    # a longer pulse is still one pulse, taken at its leading edge
    plc, mod = make()
    mod.sync_pulse(width_us=250 * MS)
    plc.advance(0.5)
    assert mod.timebase.pulses == 1 and plc.read(f"I{SLOT},7") == 1


def test_7_2_positive_or_negative_pulse_judged_like_an_input() -> None:
    # 7.2 "accepts a positive or negative pulse"; "identical characteristics to
    # 24-Input modules": type 1, 24 V: ON at 15 V or more, OFF at 5 V or less
    plc, mod = make()
    mod.set_sync_input(-24.0)
    plc.advance(0.001)
    mod.set_sync_input(0.0)
    assert mod.timebase.pulses == 1
    mod.set_sync_input(12.0)  # in the transition zone: the input keeps its state (off)
    plc.advance(0.01)
    mod.set_sync_input(0.0)
    assert mod.timebase.pulses == 1 and mod.sync_input.ignored == 0
    mod.set_sync_input(True)
    plc.advance(0.0003)
    mod.set_sync_input(False)  # 300 us: filtered out
    assert mod.timebase.pulses == 1 and mod.sync_input.ignored == 1


def test_7_2_the_48_v_module_judges_its_sync_input_at_48_v_limits() -> None:
    plc, mod = make("TSX DEM 2413")
    mod.set_sync_input(24.0)  # below the 34 V ON limit of the DEM 2413
    plc.advance(0.01)
    assert mod.timebase.pulses == 0
    mod.set_sync_input(48.0)
    plc.advance(0.01)
    assert mod.timebase.pulses == 1


def test_1_2_1_out_syn_repeats_the_input_and_each_module_filters_it() -> None:
    # "This signal is an amplification of the synchronization input"
    plc, a = make()
    b = plc.insert("TSX DEM 2412", rack=0, slot=5)
    plc.advance(10.1)
    a.connect_sync_output(b)
    a.sync_pulse(width_us=200)
    plc.advance(0.02)
    assert (a.sync_input.ignored, b.sync_input.ignored) == (1, 1)
    assert a.timebase.pulses == b.timebase.pulses == 0
    a.sync_pulse()
    plc.advance(0.02)
    assert a.timebase.pulses == b.timebase.pulses == 1


@pytest.mark.parametrize("width", [0, -5, True, 1.5])
def test_a_pulse_width_must_be_a_positive_number_of_microseconds(width: object) -> None:
    plc, mod = make()
    with pytest.raises(ConfigError, match="sync pulse width"):
        mod.sync_pulse(width_us=width)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="sync pulse width"):
        mod.attach_pulse_source(S, width_us=width)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="sync input"):
        mod.set_sync_input("high")  # type: ignore[arg-type]


def test_1_2_1_a_pulse_train_on_in_syn_counts_only_pulses_past_the_filter() -> None:
    plc, mod = make()
    start = plc.clock.now + S
    mod.set_sync_signal(PulseTrain(period_us=S, duty=0.0004, start_us=start))  # 400 us
    plc.advance(3.01)
    assert mod.timebase.pulses == 0 and mod.sync_input.ignored == 3
    mod.set_sync_signal(PulseTrain(period_us=S, duty=0.001, start_us=plc.clock.now))  # 1 ms
    plc.advance(2.5)
    assert mod.timebase.pulses == 3 and mod.sync_input.taken == 3
    mod.set_sync_signal(None)
    plc.advance(2.0)
    assert mod.timebase.pulses == 3


def test_taking_the_signal_off_in_syn_leaves_the_input_at_rest() -> None:
    plc, mod = make()
    mod.set_sync_signal(PulseTrain(period_us=S, duty=0.5, start_us=plc.clock.now))
    plc.advance(0.1)
    assert mod.sync_input.active and mod.timebase.pulses == 1
    mod.set_sync_signal(None)
    assert not mod.sync_input.active and mod.sync_input.state is SyncLevel.REST
