"""The pytest plugin in a fresh project (pytester): fixtures plant, plc, tes, the
marker plant, the fixtures advance_to and run_until, and their failure messages."""

from __future__ import annotations

import importlib.metadata

import pytest

from tests.plugin.project import user_project, write

TANK_TEST = """
import pytest
from fieldtwin.testing import assert_object

@pytest.mark.plant("plants/aem811_tank.toml")
def test_program_configures_the_module(plant, plc, run_until):
    assert plant.title == "AEM 811 four tanks (AEM 5.1)"
    assert plc is plant.plc and plc.now_s == 0
    run_until(lambda: plc.read("B3"), within=30)   # the program's "configured" bit
    assert_object(plc, "IW5,0,C", 1)
    run_until(lambda: plc.read("W0") > 0, within=1)
    assert_object(plant, "W0", 5000, tolerance=5)
"""


def test_the_plugin_is_an_installed_pytest11_entry_point() -> None:
    points = importlib.metadata.entry_points(group="pytest11")
    assert "fieldtwin.testing.plugin" in {p.value for p in points if p.name == "fieldtwin"}


def test_fixtures_and_marker_are_listed_in_a_fresh_project(pytester: pytest.Pytester) -> None:
    user_project(pytester)
    fixtures = pytester.runpytest_subprocess("--fixtures")
    for name in ("plant", "plc", "tes", "running_plant", "advance_to", "run_until"):
        fixtures.stdout.fnmatch_lines([f"{name} -- *fieldtwin*testing*plugin.py*"])
    markers = pytester.runpytest_subprocess("--markers")
    markers.stdout.fnmatch_lines(["@pytest.mark.plant(path=None, *, tes=None, speed=None*"])


def test_marker_path_relative_to_the_rootdir_and_to_the_test_file(
    pytester: pytest.Pytester,
) -> None:
    user_project(pytester, "aem811_tank.toml", "aem811_tank.pl7")
    write(pytester, "tests/test_tank.py", TANK_TEST)
    write(pytester, "tests/here/tank.toml", (pytester.path / "plants/aem811_tank.toml").read_text())
    (pytester.path / "tests/here/aem811_tank.pl7").write_text(
        (pytester.path / "plants/aem811_tank.pl7").read_text()
    )
    write(
        pytester,
        "tests/here/test_here.py",
        TANK_TEST.replace("plants/aem811_tank.toml", "tank.toml"),
    )
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=2)


def test_default_plant_tes_marker_option_and_indirect_parameters(
    pytester: pytest.Pytester,
) -> None:
    user_project(pytester, "tes.toml", "aem811.toml")
    write(
        pytester,
        "tests/test_fixtures.py",
        """
import pytest

def test_default_plant(plant, plc, tes):
    assert plant.name == "<default plant>"
    assert tes.model.name == "TES 32EST" and tes.slave == 1
    assert tes.clock is plc.clock is plant.clock       # one simulated clock
    assert plant.bindings == []                          # no endpoint opened

@pytest.mark.plant(tes=2)
def test_tes_by_slave(tes):
    assert tes.model.name == "TES 8EA"

@pytest.mark.parametrize("plant", ["plants/tes.toml", "plants/aem811.toml"], indirect=True)
def test_each_plant(plant, advance_to):
    advance_to(2.5)
    assert plant.clock.now == 2_500_000
""",
    )
    write(
        pytester,
        "tests/test_module_marker.py",
        """
import pytest

pytestmark = pytest.mark.plant("plants/aem811.toml")

def test_module_marker(plant):
    assert plant.name.endswith("aem811.toml")

@pytest.mark.plant("plants/tes.toml")
def test_the_closest_marker_wins(plant):
    assert plant.name.endswith("tes.toml")
""",
    )
    result = pytester.runpytest("-p", "no:cacheprovider", "-v")
    result.assert_outcomes(passed=6)


def test_every_test_gets_a_new_plant_at_time_zero(pytester: pytest.Pytester) -> None:
    user_project(pytester)
    write(
        pytester,
        "tests/test_fresh.py",
        """
import pytest

@pytest.mark.parametrize("n", [1, 2])
def test_fresh(plc, advance_to, n):
    assert plc.now_s == 0 and plc.read("W100") == 0
    plc.write("W100", 7)
    advance_to(1)
""",
    )
    pytester.runpytest("-p", "no:cacheprovider").assert_outcomes(passed=2)


def test_failure_messages_name_time_values_and_object(pytester: pytest.Pytester) -> None:
    user_project(pytester, "aem811_tank.toml", "aem811_tank.pl7")
    write(
        pytester,
        "tests/test_fails.py",
        """
import pytest
from fieldtwin.testing import assert_object, assert_leds

pytestmark = pytest.mark.plant("plants/aem811_tank.toml")

def test_level_never_that_high(plc, run_until):
    run_until(lambda: plc.read("W0") > 9000, within=20, show=["W0", "IW5,0,C"])

def test_wrong_level(plant, advance_to):
    advance_to(12)
    assert_object(plant, "W0", 7000)

def test_wrong_led(plant, advance_to):
    advance_to(12)
    assert_leds(plant, {"ERR": "on"}, device="5")

def test_time_goes_forward_only(advance_to):
    advance_to(3)
    advance_to(1)
""",
    )
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(failed=4)
    plant = "plants/aem811_tank.toml"
    result.stdout.fnmatch_lines(
        [
            f'E *NotWithin: run_until on plant *{plant}: lambda: plc.read("W0") > 9000'
            " not true within 20 s (from t = 0.000 s to t = 20.000 s)",
            "E *  last value of the predicate: False",
            "E *  at t = 20.000 s: W0 = 5001 (H'1389'), IW5,0,C = 1",
            f"E *AssertionError: W0 of plant *{plant}: expected 7000 (H'1B58'),"
            " actual 5001 (H'1389') at t = 12.000 s",
            f"E *AssertionError: LED ERR of TSX AEM 811 5 of plant *{plant}: expected 'on',"
            " actual 'off' (OK=on ERR=off F=off) at t = 12.000 s",
            f"E *AssertionError: advance_to(1) on plant *{plant}: cannot advance to t = 1 s:"
            " simulated time is already 3.000 s and never goes back",
        ],
        consecutive=False,
    )
    # the failing line of the test is shown, not the helper's insides
    assert "fieldtwin/testing/helpers.py" not in result.stdout.str()


def test_marker_mistakes_are_reported_naming_the_test(pytester: pytest.Pytester) -> None:
    user_project(pytester)
    write(pytester, "plants/bad.toml", '[plc]\nmodel = "TSX 99"\n')
    write(
        pytester,
        "plants/only_tes.toml",
        '[[tes]]\nmodel = "TES 8EA"\nslave = 2\nendpoint = "tcp://127.0.0.1:5020"\n',
    )
    write(
        pytester,
        "tests/test_mistakes.py",
        """
import pytest

@pytest.mark.plant("plants/nowhere.toml")
def test_missing(plant): pass

@pytest.mark.plant("plants/bad.toml")
def test_bad(plant): pass

@pytest.mark.plant(color="red")
def test_unknown_option(plant): pass

@pytest.mark.plant("plants/only_tes.toml")
def test_no_plc(plc): pass

@pytest.mark.plant("plants/only_tes.toml", tes=5)
def test_no_such_tes(tes): pass
""",
    )
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(errors=5)
    out = result.stdout.str()
    assert (
        "tests/test_mistakes.py::test_missing: @pytest.mark.plant: no plant file"
        " 'plants/nowhere.toml' (looked for " in out
    )
    assert "plants/bad.toml: plc.model: 'TSX 99' not allowed (allowed: TSX 47-20" in out
    assert "plant fixture: /" in out  # the file named by its path
    assert "unknown keyword(s) color (allowed: tes, speed, args)" in out
    assert "only_tes.toml has no PLC (no [plc] and no [[module]])" in out
    assert "no TES with slave number 5 in this plant (have:" in out
