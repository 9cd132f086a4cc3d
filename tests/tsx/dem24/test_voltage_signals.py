"""Voltage signals judged continuously against the type 1 limits (DEM 7.2, 2.3-2).

The module cycle is under a millisecond (7.2), so a ramp or a sine that crosses
15 V (24 V module) between two breakpoints is time-stamped at the crossing, to the
millisecond, not at the next breakpoint.
"""

from __future__ import annotations

import math

from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.signals import Constant, PiecewiseLinear, Ramp, Sine, Sum
from fieldtwin.tsx.dem24.crossing import crossed_test, next_event
from fieldtwin.tsx.dem24.inputs import TYPE1_24V, TYPE1_48V
from tests.tsx.dem24.helpers import SLOT, at, read_all, stamp, synced

SET_AT_US = 71 * S  # synced(): 18:06:00.000 at t = 71 s


def expected_stamp(t_us: int) -> tuple[int, int, int, int, int, int, int]:
    ms = (t_us - SET_AT_US) // MS
    minute, rest = divmod(6 * 60_000 + ms, 60_000)
    return (94, 7, 15, 18, minute, rest // 1000, rest % 1000)


def changes(channel: int) -> list[tuple[int, tuple[int, int, int, int, int, int, int]]]:
    return [(m[7] & 0xFF, stamp(m)) for m in channel_msgs(channel)]


def channel_msgs(channel: int) -> list[list[int]]:
    return [m for m in _msgs if m[7] >> 8 == channel and not (m[1] >> 10) & 1]


_msgs: list[list[int]] = []


def test_7_2_ramp_stamped_where_it_crosses_15_v_and_5_v() -> None:
    plc, mod = synced()
    # 0 V at 72 s up to 24 V at 74.4 s, held, then down to 0 V from 80 s to 82.4 s
    signal = PiecewiseLinear([(72 * S, 0.0), (74_400_000, 24.0), (80 * S, 24.0), (82_400_000, 0)])
    mod.set_signal(3, signal)
    at(plc, 73.49)
    assert plc.read(f"IW{SLOT},6,3") == 0  # 14.9 V: still OFF (no breakpoint yet)
    at(plc, 73.52)
    assert plc.read(f"IW{SLOT},6,3") == 1
    at(plc, 90.0)
    _msgs[:] = read_all(plc)
    # ON at 15 V: 72 + 1.5 s; OFF at 5 V: 80 + 2.4 * 19 / 24 = 81.9 s
    assert changes(3) == [(1, expected_stamp(73_500_000)), (0, expected_stamp(81_900_000))]


def test_7_2_ramp_object_on_the_48_v_module() -> None:
    plc, mod = synced(type_name="TSX DEM 2413")
    mod.set_signal(0, Ramp(0.0, 48.0, 72 * S, 4_800_000))  # 10 V per second
    at(plc, 80.0)
    _msgs[:] = read_all(plc)
    assert changes(0) == [(1, expected_stamp(75_400_000))]  # 34 V at 72 + 3.4 s


def _sine_times(offset: float, amplitude: float, period_s: float) -> tuple[float, float]:
    on = math.asin((15.0 - offset) / amplitude) / (2 * math.pi) * period_s
    off = (math.pi + math.asin((offset - 5.0) / amplitude)) / (2 * math.pi) * period_s
    return on, off


def test_7_2_sine_stamped_at_its_crossings() -> None:
    plc, mod = synced()
    mod.set_signal(7, Sine(12.0, 12.0, 4 * S))
    at(plc, 80.0)
    _msgs[:] = read_all(plc)
    on, off = _sine_times(12.0, 12.0, 4.0)
    want = []
    for k in (18, 19):  # periods starting at 72 s and 76 s
        want += [(1, math.ceil((4 * k + on) * S)), (0, math.ceil((4 * k + off) * S))]
    assert changes(7) == [(level, expected_stamp(t)) for level, t in want]


def test_7_2_any_smooth_signal_is_sampled_each_millisecond() -> None:
    plc, mod = synced()
    mod.set_signal(8, Sum([Sine(12.0, 12.0, 4 * S), Constant(0.0)]))
    mod.set_signal(9, Sine(12.0, 12.0, 4 * S))
    at(plc, 80.0)
    _msgs[:] = read_all(plc)
    assert [c[1] for c in changes(8)] == [c[1] for c in changes(9)]
    assert len(changes(8)) == 4


def test_a_sine_inside_the_transition_zone_never_switches() -> None:
    plc, mod = synced()
    mod.set_signal(2, Sine(10.0, 4.0, 2 * S))  # 6 V .. 14 V: never ON
    assert mod.inputs._ch[2].signal_handle is None  # event-driven: nothing to wait for
    at(plc, 80.0)
    assert plc.read(f"IW{SLOT},6,2") == 0 and read_all(plc) == []


def test_next_event_bisects_to_the_microsecond() -> None:
    ramp = Ramp(0.0, 30.0, 0, 3 * S)  # 10 V/s: 15 V at 1.5 s, then constant
    assert next_event(ramp, 0, False, TYPE1_24V) == 1_500_000
    assert next_event(ramp, 1_500_000, True, TYPE1_24V) == 3 * S  # no OFF: its end
    assert next_event(ramp, 3 * S, True, TYPE1_24V) is None
    down = Ramp(60.0, 0.0, 0, 6 * S)
    assert next_event(down, 0, True, TYPE1_48V) == 5 * S  # 10 V at 5 s
    assert next_event(Sine(0.0, 4.0, S), 0, False, TYPE1_24V) is None


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-30.0, 30.0),
    st.floats(-30.0, 30.0),
    st.integers(0, 5 * S),
    st.integers(1, 5 * S),
    st.booleans(),
)
def test_ramp_crossing_is_the_first_microsecond_past_the_limit(
    start: float, end: float, t0: int, duration: int, level: bool
) -> None:
    ramp = Ramp(start, end, t0, duration)
    crossed, _ = crossed_test(TYPE1_24V, level)
    assume(not crossed(start))
    t: int | None = 0
    for _ in range(5):  # walk the events as the module does: at most breakpoints + 1
        assert t is not None
        t = next_event(ramp, t, level, TYPE1_24V)
        if t is None or crossed(ramp.value_at(t)):
            break
    if t is None or not crossed(ramp.value_at(t)):
        assert not crossed(end)  # a ramp that never reaches the limit never switches
    else:  # monotonic: the first microsecond past the limit, and the previous one is not
        assert not crossed(ramp.value_at(t - 1))


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-10.0, 30.0),
    st.floats(0.5, 30.0),
    st.integers(10 * MS, 2 * S),
    st.floats(0.0, 360.0),
    st.integers(0, 3 * S),
)
def test_sine_crossing_has_no_earlier_millisecond(
    offset: float, amplitude: float, period: int, phase: float, t: int
) -> None:
    sine = Sine(offset, amplitude, period, phase)
    level = sine.value_at(t) >= 15.0
    crossed, _ = crossed_test(TYPE1_24V, level)
    assume(not crossed(sine.value_at(t)))
    got = next_event(sine, t, level, TYPE1_24V)
    limit = got if got is not None else t + period
    assert not any(crossed(sine.value_at(u)) for u in range(t + 1, limit, 250))
    if got is not None:
        assert crossed(sine.value_at(got)) and not crossed(sine.value_at(got - 1))
