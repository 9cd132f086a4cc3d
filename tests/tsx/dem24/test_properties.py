"""Property tests: edges in = messages out; the civil calendar; the time-base machine."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.errors import ProtocolError
from fieldtwin.tsx.dem24.civil import CivilTime, civil_from_days, days_from_civil, is_leap
from fieldtwin.tsx.dem24.timebase import SyncEvent, Timebase, TimeReference, TimeState
from tests.tsx.dem24.helpers import read_all, synced

SET_AT_US = 71 * S  # synced(): 18:06:00.000 taken at t = 71 s
SET_AT_MS = CivilTime(1994, 7, 15, 18, 6, 0).to_ms()
SELECTED = (0, 5, 15, 16, 23)

edges = st.lists(
    st.tuples(st.sampled_from(SELECTED), st.integers(min_value=1, max_value=4000)),
    min_size=1,
    max_size=60,
)


@settings(max_examples=30, deadline=None)
@given(edges)
def test_edges_read_back_exactly_in_order_with_millisecond_times(
    steps: list[tuple[int, int]],
) -> None:
    # filter 0, no oscillation detection, fewer than 200 messages
    plc, mod = synced(select=sum(1 << c for c in SELECTED))
    t = -(-plc.now // MS) * MS + 10 * MS
    expected = []
    levels = dict.fromkeys(SELECTED, False)
    for channel, gap_ms in steps:
        t += gap_ms * MS
        plc.clock.run_until(t)
        levels[channel] = not levels[channel]
        mod.set_input(channel, levels[channel])
        offset = (t - SET_AT_US) // MS
        expected.append((channel, int(levels[channel]), CivilTime.from_ms(SET_AT_MS + offset)))
    plc.advance(1.0)
    got = [
        (
            m[7] >> 8,
            m[7] & 0xFF,
            (m[2] >> 8, m[2] & 0xFF, m[3] >> 8, m[3] & 0xFF, m[4] >> 8, m[4] & 0xFF, m[5]),
        )
        for m in read_all(plc)
    ]
    want = [
        (ch, st_, (c.yy, c.month, c.day, c.hour, c.minute, c.second, c.ms))
        for ch, st_, c in expected
    ]
    assert got == want


@given(st.integers(min_value=-800_000, max_value=800_000))
def test_civil_days_round_trip(days: int) -> None:
    assert days_from_civil(*civil_from_days(days)) == days


@given(st.integers(min_value=0, max_value=4_000_000_000_000))
def test_civil_ms_round_trip(value: int) -> None:
    civil = CivilTime.from_ms(value)
    assert civil.to_ms() == value
    assert 0 <= civil.hour < 24 and 1 <= civil.day <= 31


def test_leap_years() -> None:
    assert is_leap(1996) and is_leap(2000) and not is_leap(1900) and not is_leap(1995)
    assert days_from_civil(1970, 1, 1) == 0
    assert days_from_civil(1994, 7, 15) == 8961
    assert CivilTime.from_ms(CivilTime(1996, 2, 28, 23, 59, 59, 999).to_ms() + 1) == CivilTime(
        1996, 2, 29, 0, 0, 0, 0
    )


def test_time_table_round_trip() -> None:
    ref = TimeReference.decode(bytes([0x07, 0x5E, 0x12, 0x0F, 0x21, 0x05, 0x01, 0x00]))
    assert ref == TimeReference(CivilTime(1994, 7, 15, 18, 5, 33), 1)
    assert ref.encode() == [0x5E07, 0x0F12, 0x0521, 0x0001]


@given(st.lists(st.sampled_from(list(SyncEvent)), max_size=30))
def test_time_base_machine_ends_legal_or_in_a_protocol_error(events: list[SyncEvent]) -> None:
    tb = Timebase(t_syn_s=1, drift_ms=10)
    ref = TimeReference(CivilTime(1994, 7, 15, 18, 5, 33), 1)
    t = 0
    for event in events:
        t += S
        try:
            if event is SyncEvent.REFERENCE:
                tb.reference(ref, t)
            elif event is SyncEvent.PULSE_LOST:
                tb.pulse_lost(t)
            else:
                tb.pulse(t)
        except ProtocolError as exc:
            assert event is SyncEvent.PULSE_LOST and "can't handle" in str(exc)
            assert tb.state in (TimeState.NOT_SET, TimeState.RECEIVED)
        assert tb.state in TimeState
        assert tb.ready == (tb.state in (TimeState.SET, TimeState.SET_RECEIVED))
