"""Ranges, scaling, square root and hysteresis: the tables of AEM 2.3 as vectors."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.tsx.aem811.ranges import LSB_MV, RANGES, range_by_name, round_half_away
from fieldtwin.tsx.aem811.scaling import (
    ChannelConfig,
    Scaling,
    extended_zone,
    hysteresis,
    measure,
    square_root,
)

A, B, C = Scaling.INPUT_RANGE, Scaling.STANDARD, Scaling.USER

# AEM 2.3-1 / 2.3-3: number, LL, HL, ELL, EHL (range units: mV, µA)
ZONES = [
    (0, -10000, 10000, -11000, 11000),
    (1, -5000, 5000, -5500, 5500),
    (2, 0, 10000, -200, 11000),
    (3, 2000, 10000, 1840, 10800),
    (4, 0, 5000, -100, 5500),
    (5, 0, 2000, -40, 2200),
    (6, 400, 2000, 368, 2160),
    (7, 0, 20000, -400, 22000),
    (8, 4000, 20000, 3680, 21600),
]


def mv(rng_number: int, value: float) -> float:
    """A value in the range unit -> terminal millivolts."""
    return RANGES[rng_number].to_mv(value)


@pytest.mark.parametrize(("number", "low", "high", "ell", "ehl"), ZONES)
def test_2_3_3_input_range_zones(number: int, low: int, high: int, ell: int, ehl: int) -> None:
    cfg = ChannelConfig(number, scaling=A)
    r = RANGES[number]
    assert (r.low, r.high, r.ell, r.ehl) == (low, high, ell, ehl)
    assert extended_zone(cfg) == (ell, ehl)
    for value in (low, high, ell, ehl):  # the limits themselves: no fault
        m = measure(mv(number, value), cfg, quantize=False)
        assert m.value == value and not m.faulty
    # AEM 2.3-1: beyond the extended range, the limit and the ELL/EHL fault
    span = high - low
    below = measure(mv(number, ell - span / 100), cfg)
    above = measure(mv(number, ehl + span / 100), cfg)
    assert (below.value, below.below, below.above) == (ell, True, False)
    assert (above.value, above.below, above.above) == (ehl, False, True)


@pytest.mark.parametrize(("number", "low", "high", "ell", "ehl"), ZONES)
def test_quantized_limits_raise_no_fault(
    number: int, low: int, high: int, ell: int, ehl: int
) -> None:
    # the converter's own limit codes: an input exactly at ELL/EHL is inside
    cfg = ChannelConfig(number, scaling=A)
    tolerance = 4 if RANGES[number].current else 1  # one 0.33 mV step, in µA
    for value in (low, high, ell, ehl):
        m = measure(mv(number, value), cfg)
        assert abs(m.value - value) <= tolerance and not m.faulty


def test_2_3_1_example_0_10_v_in_mv() -> None:
    cfg = ChannelConfig(2, scaling=A)
    assert measure(5000, cfg) == measure(5000, cfg, quantize=False)
    assert measure(5000, cfg).value == 5000  # 1: normal
    m = measure(-150, cfg)  # 2: extended zone, exact value
    assert m.value == -150 and not m.faulty
    assert measure(10500, cfg).value == 10500
    m = measure(-300, cfg)  # 3: below ELL (-0.2 V): -200, ELL = 1
    assert (m.value, m.below, m.above) == (-200, True, False)
    m = measure(11500, cfg)  # 4: above EHL (+11 V): 11000, EHL = 1
    assert (m.value, m.below, m.above) == (11000, False, True)


@pytest.mark.parametrize("number", [2, 3, 4, 5, 6, 7, 8])
def test_2_3_3_standard_unipolar(number: int) -> None:
    assert extended_zone(ChannelConfig(number, scaling=B)) == (-200, 11000)
    assert extended_zone(ChannelConfig(number, True, B)) == (-1414, 10488)
    r = RANGES[number]
    m = measure(mv(number, r.low + (r.high - r.low) / 2), ChannelConfig(number, scaling=B))
    assert abs(m.value - 5000) <= 1  # AMB-AEM-32: 0 % at LL


@pytest.mark.parametrize("number", [0, 1])
def test_2_3_3_standard_bipolar(number: int) -> None:
    assert extended_zone(ChannelConfig(number, scaling=B)) == (-11000, 11000)
    assert extended_zone(ChannelConfig(number, True, B)) == (-10488, 10488)


def test_2_3_2_square_root_convention() -> None:
    assert square_root(10000) == 10000  # 100 x sqrt(100.00 %)
    assert square_root(2500) == 5000
    assert square_root(-2500) == -5000  # negative: -100 x sqrt(-m)
    # input range scaling never takes the root (refused at configuration)
    cfg = ChannelConfig(2, True, B)
    assert measure(2500, cfg, quantize=False).value == 5000  # standardize, then root


def test_2_3_3_user_example_2_to_20_bar() -> None:
    # 0/20 mA, 2 bar = 0 mA, 20 bar = 20 mA, limits 2000..20000 (1 mbar)
    cfg = ChannelConfig(7, scaling=C, high=20000, low=2000)
    assert extended_zone(cfg) == (1640, 21800)
    assert measure(mv(7, 10000), cfg, quantize=False).value == 11000  # 10 mA: 11 bar


def test_2_3_3_user_extended_zones() -> None:
    # unipolar: LL - 2 %, HL + 10 %; bipolar: LL - 5 %, HL + 5 %
    assert extended_zone(ChannelConfig(2, scaling=C, high=1000, low=0)) == (-20, 1100)
    assert extended_zone(ChannelConfig(0, scaling=C, high=1000, low=0)) == (-50, 1050)
    assert extended_zone(ChannelConfig(8, scaling=C, high=10000, low=0)) == (-200, 11000)


def test_4_1_3_correspondence_examples() -> None:
    five_volts = 5000.0
    assert measure(five_volts, ChannelConfig(2, scaling=A)).value == 5000  # 5000 mV
    assert measure(five_volts, ChannelConfig(2, scaling=B)).value == 5000  # 50.00 %
    user = ChannelConfig(2, scaling=C, high=1000, low=200)
    assert measure(five_volts, user).value == 600  # 5 x (1000 - 200) / 10 + 200


def test_3_2_3_channel_2_user_bipolar() -> None:
    cfg = ChannelConfig(0, scaling=C, high=8800, low=880)  # -10/+10 V, 880..8800
    assert measure(0, cfg, quantize=False).value == 4840
    assert measure(10000, cfg, quantize=False).value == 8800
    assert measure(-10000, cfg, quantize=False).value == 880


def test_amb_aem_18_square_root_user_zone() -> None:
    # 0/10 V, square root, 0..20000: ELL -> -2828, EHL -> 20976 (AEM 5.1 flow channels)
    cfg = ChannelConfig(2, True, C, high=20000, low=0)
    assert extended_zone(cfg) == (-2828, 20976)
    assert measure(5625, cfg, quantize=False).value == 15000  # 15 l/min at 5.625 V


def test_calculation_overflow_saturates() -> None:
    cfg = ChannelConfig(2, scaling=C, high=32767, low=0)  # HL + 10 % does not fit
    m = measure(10800, cfg)
    assert m.value == 32767 and m.overflow and not m.above
    m = measure(10000, cfg, quantize=False)
    assert m.value == 32767 and not m.overflow
    low = ChannelConfig(2, scaling=C, high=0, low=-32768)
    assert measure(11500, low).value == 3277 and measure(-300, low).overflow


def test_open_input_reads_ehl() -> None:
    # AEM 2.3-4: an open voltage input reads EHL; the continuity test flags it
    cfg = ChannelConfig(2, scaling=A, continuity=True)
    m = measure(None, cfg, tested=True)
    assert (m.value, m.continuity, m.above) == (11000, True, False)
    assert not measure(None, cfg, tested=False).faulty
    # 4/20 mA: a cut line is 0 mA, an under-range; 0/20 mA cannot tell
    assert measure(None, ChannelConfig(8, scaling=A)).below
    m = measure(None, ChannelConfig(7, scaling=A))
    assert m.value == 0 and not m.faulty


def test_quantization_step() -> None:
    # AEM 8.2: 11000/32768 mV = 0.33 mV; steps smaller than that are not seen
    cfg = ChannelConfig(0, scaling=C, high=32767, low=-32768)
    assert pytest.approx(0.3357, abs=1e-4) == LSB_MV
    base = measure(1000.0, cfg).value
    assert measure(1000.0 + LSB_MV / 4, cfg).value == base
    assert measure(1000.0 + LSB_MV, cfg).value > base
    assert measure(1000.0 + LSB_MV / 4, cfg, quantize=False).value > base


HYSTERESIS = {0: 100, 1: 50, 2: 50, 3: 40, 4: 26, 5: 10, 6: 8, 7: 100, 8: 80}


@pytest.mark.parametrize(("number", "h"), sorted(HYSTERESIS.items()))
def test_2_3_5_hysteresis_table(number: int, h: int) -> None:
    assert hysteresis(ChannelConfig(number, scaling=A)) == h
    assert hysteresis(ChannelConfig(number, scaling=B)) == 50


def test_2_3_5_user_hysteresis_formula() -> None:
    # 2 x (Integer of ((HL - LL) x 25.10^-4) + 1)  (AMB-AEM-11)
    assert hysteresis(ChannelConfig(8, scaling=C, high=10000, low=0)) == 52
    assert hysteresis(ChannelConfig(2, scaling=C, high=1000, low=200)) == 6
    assert hysteresis(ChannelConfig(2, scaling=C, high=0, low=20000)) == 102


def test_range_names() -> None:
    assert range_by_name("4/20mA") is RANGES[8]
    assert range_by_name("-10/+10 V") is RANGES[0]
    assert range_by_name("0-10V") is RANGES[2]
    assert range_by_name("3/15V") is None


def test_round_half_away() -> None:
    assert [round_half_away(x) for x in (0.5, 1.5, -0.5, -1.5, 2.4)] == [1, 2, -1, -2, 2]


configs = st.builds(
    ChannelConfig,
    st.integers(0, 8),
    st.booleans(),
    st.sampled_from([B, C]),
    st.just(False),
    st.integers(-32768, 32767),
    st.integers(-32768, 32767),
).filter(lambda c: c.high != c.low)


@given(configs, st.floats(-20000, 20000), st.floats(-20000, 20000))
def test_measurement_is_monotonic_and_inside_the_zone(
    cfg: ChannelConfig, a: float, b: float
) -> None:
    lo_mv, hi_mv = sorted((a, b))
    m_lo, m_hi = measure(lo_mv, cfg), measure(hi_mv, cfg)
    if cfg.scaling is B or cfg.high > cfg.low:
        assert m_lo.value <= m_hi.value
    else:
        assert m_lo.value >= m_hi.value
    zone = sorted(extended_zone(cfg))
    if not (m_lo.overflow or m_hi.overflow):
        assert zone[0] <= m_lo.value <= zone[1]
