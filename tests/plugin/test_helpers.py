"""fieldtwin.testing's time helpers and assertions on in-process plants, PLCs and TES:
every failure names the object, the expected and the actual value and the simulated time."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.plant import Plant, build_plant, read_plant
from fieldtwin.tes import Tes
from fieldtwin.testing import (
    NotWithin,
    advance_to,
    assert_leds,
    assert_object,
    assert_state,
    run_until,
)
from fieldtwin.tsx.plc import Plc

ROOT = Path(__file__).resolve().parents[2]
TANK = ROOT / "examples" / "aem811_tank.toml"


@pytest.fixture()
def tank() -> Plant:
    return build_plant(read_plant(TANK), speed=None)


def test_run_until_stops_at_the_first_instant_the_predicate_holds(tank: Plant) -> None:
    plc = tank.plc
    assert plc is not None
    value = run_until(tank, lambda: plc.read("W0"), within=30)
    assert value == plc.read("W0") > 0
    # one scan earlier it did not hold: the run stopped at the first instant it did
    assert 0 < tank.clock.now <= 30_000_000
    assert plc.now_s < 30


def test_run_until_at_the_bound_gives_time_predicate_and_values(tank: Plant) -> None:
    plc = tank.plc
    assert plc is not None
    advance_to(tank, 15)
    with pytest.raises(NotWithin) as caught:
        run_until(tank, lambda: plc.read("W0") > 9000, within=2.5, show=["W0", "I5,S"])
    text = str(caught.value)
    assert text.splitlines()[0] == (
        f'run_until on plant {TANK}: lambda: plc.read("W0") > 9000 not true within 2.5 s'
        " (from t = 15.000 s to t = 17.500 s)"
    )
    assert "last value of the predicate: False" in text
    assert "at t = 17.500 s: W0 = 5001 (H'1389'), I5,S = 0" in text
    assert caught.value.t_s == 17.5
    assert caught.value.values == {"W0": 5001, "I5,S": 0}
    assert plc.now_s == 17.5


def test_run_until_shows_the_plc_watch_list_by_default(tank: Plant) -> None:
    plc = tank.plc
    assert plc is not None
    with pytest.raises(NotWithin) as caught:
        run_until(tank, lambda: False, within=1)
    assert "W0 = 0, W1 = 0, W2 = 0, W3 = 0, W4 = 0, W5 = 0, W6 = 0, W7 = 0" in str(caught.value)


def test_run_until_with_a_step_and_a_named_function() -> None:
    tes = Tes("TES 32EST", slave=1)

    def input_3_seen() -> bool:
        return bool(tes.peek(0x005) & 0x8)

    assert run_until(tes, lambda: tes.now_s > 0.3, within=1, step=0.25) is True
    assert tes.now_s == 0.5  # checked every 0.25 s only
    tes.set_input("3", True)
    assert run_until(tes, input_3_seen, within=1) is True

    def input_3_off() -> bool:
        return not input_3_seen()

    with pytest.raises(NotWithin, match=r"<locals>.input_3_off not true within 0.5 s"):
        run_until(tes, input_3_off, within=0.5, show=[])
    # the line's lambda is cut where the call's argument ends
    with pytest.raises(NotWithin, match=r"slave 1: lambda: not input_3_seen\(\) not true"):
        run_until(tes, lambda: not input_3_seen(), within=0.01, show=["0x005"])


def test_run_until_refuses_a_bound_that_is_not_one(tank: Plant) -> None:
    for within in (-1, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="a bound in simulated seconds"):
            run_until(tank, lambda: True, within=within)
    with pytest.raises(ValueError, match="step=0"):
        run_until(tank, lambda: True, within=1, step=0)


def test_advance_to_never_goes_back() -> None:
    plc = Plc()
    advance_to(plc, 2.5)
    assert plc.now_s == 2.5
    with pytest.raises(AssertionError) as caught:
        advance_to(plc, 1)
    assert str(caught.value) == (
        "advance_to(1) on PLC TSX 87: cannot advance to t = 1 s: simulated time is"
        " already 2.500 s and never goes back"
    )


def test_assert_object_names_object_expected_actual_and_time(tank: Plant) -> None:
    advance_to(tank, 12)
    assert assert_object(tank, "W0", 5001) == 5001
    assert_object(tank, "W0", 5000, tolerance=1)
    with pytest.raises(AssertionError) as caught:
        assert_object(tank, "W0", 4000, tolerance=10)
    assert str(caught.value) == (
        f"W0 of plant {TANK}: expected 4000 (H'0FA0') ± 10, actual 5001 (H'1389') at t = 12.000 s"
    )
    with pytest.raises(AssertionError, match=r"I5,S of plant .*: expected 1, actual 0 at t = 12"):
        assert_object(tank, "I5,S", 1)


def test_assert_object_on_a_device_and_a_tes_and_signed() -> None:
    tes = Tes("TES 32EST", slave=4)
    tes.set_input("0", True)
    advance_to(tes, 0.1)
    assert_object(tes, "0x005", 1)
    assert_object(tes, "H'005'", 1)
    with pytest.raises(AssertionError) as caught:
        assert_object(tes, "0x005", 0)
    assert str(caught.value) == "0x005 of TES 32EST slave 4: expected 0, actual 1 at t = 0.100 s"
    plc = Plc()
    plc.write("W9", -5)
    assert_object(plc, "W9", -5, signed=True)
    with pytest.raises(AssertionError, match=r"W9 of PLC TSX 87: expected -4, actual -5 at"):
        assert_object(plc, "W9", -4, signed=True)
    with pytest.raises(AssertionError, match=r"QW5,0 of PLC TSX 87: "):
        assert_object(plc, "QW5,0", 0)


def test_assert_object_device_prefix_in_a_plant() -> None:
    plant = build_plant(read_plant(None), speed=None)
    advance_to(plant, 1)
    word = plant.tes_by_slave(1).peek(0x005)
    assert_object(plant, "tes1:0x005", word)
    with pytest.raises(AssertionError, match=r"no device 'tes9' \(have: 4, 5, 14, 16, 17, 7,"):
        assert_object(plant, "tes9:0x005", 0)


def test_assert_leds_and_state(tank: Plant) -> None:
    advance_to(tank, 12)
    assert_leds(tank, {"OK": "on", "F": "off"}, device="5")
    assert_state(tank, "operational", device="5")
    with pytest.raises(AssertionError) as caught:
        assert_leds(tank, {"ERR": "on"}, device="5")
    assert str(caught.value) == (
        f"LED ERR of TSX AEM 811 5 of plant {TANK}: expected 'on', actual 'off'"
        " (OK=on ERR=off F=off) at t = 12.000 s"
    )
    with pytest.raises(AssertionError, match=r"has no LED 'RUN' \(has: OK, ERR, F\)"):
        assert_leds(tank, {"RUN": "on"}, device="5")
    with pytest.raises(AssertionError, match=r"name the device"):
        assert_leds(tank, {"OK": "on"})
    with pytest.raises(AssertionError) as state:
        assert_state(tank, "self-test", device="5")
    assert str(state.value) == (
        f"state of TSX AEM 811 5 of plant {TANK}: expected 'self-test',"
        " actual 'operational' at t = 12.000 s"
    )
    plc = tank.plc
    assert plc is not None
    assert_leds(plc, {"OK": "on"}, device="5")
    tes = Tes("TES 8EA", slave=2)
    assert_leds(tes, {"Pwr": "on", "Wdg": "off"})
    tes.power_off()
    with pytest.raises(AssertionError, match=r"LED Pwr of TES 8EA slave 2 of TES 8EA slave 2"):
        assert_leds(tes, {"Pwr": "on"})
    with pytest.raises(AssertionError, match=r"expected 'on', actual 'off' at t = 0.000 s"):
        assert_state(tes, "on")


def test_helpers_refuse_what_is_not_a_plant() -> None:
    with pytest.raises(TypeError, match="is not a plant, a PLC, a TES or a running plant"):
        assert_object(object(), "W0", 0)
