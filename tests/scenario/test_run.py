"""Scenarios run in process on a plant (fieldtwin.testing.run_scenario): every step at
its simulated instant through the plant's door, every expectation checked."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.clock import S
from fieldtwin.plant import Plant, load_plant
from fieldtwin.runtime.door import Command
from fieldtwin.testing import run_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.fixture()
def plant() -> Plant:
    return load_plant(None)


class Seen:
    """A door observer: the outermost commands, with the simulated time they ran at."""

    def __init__(self, plant: Plant) -> None:
        self.plant = plant
        self.commands: list[tuple[float, Command]] = []

    def before(self, command: Command) -> None:
        self.commands.append((self.plant.clock.now / S, command))

    def after(self, command: Command, answer: object, error: BaseException | None) -> None:
        pass


def test_the_fault_drill_passes_on_the_default_plant(plant: Plant) -> None:
    seen = Seen(plant)
    plant.door.watch(seen)
    result = run_scenario(plant, EXAMPLES / "fault_drill.toml")
    assert result["passed"] and result["done"] and result["failure"] is None
    assert plant.clock.now == 40 * S
    assert [o["ok"] for o in result["outcomes"]] == [True] * 11
    # each step went through the door at its instant, as the control API's command
    assert [(t, c.name, c.args) for t, c in seen.commands] == [
        (20.0, "set_fault", ("5", "open_3", True, {})),
        (25.0, "power_cycle", ("tes2", 5.0)),
        (35.0, "set_fault", ("5", "open_3", False, {})),
    ]


def test_the_scada_alarm_test_passes(plant: Plant) -> None:
    assert run_scenario(plant, EXAMPLES / "scada_alarm.toml")["passed"]


def test_a_wrong_expectation_fails_naming_the_step_object_values_and_time(
    plant: Plant, tmp_path: Path
) -> None:
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(
        (EXAMPLES / "fault_drill.toml")
        .read_text()
        .replace('led = "Pwr"\nequals = "off"', 'led = "Pwr"\nequals = "on"')
    )
    with pytest.raises(AssertionError) as failed:
        run_scenario(plant, wrong)
    assert str(failed.value) == (
        "expect[5] at t = 26.000 s: tes2 LED Pwr expected 'on', actual 'off'"
        " (after step[2] power_off tes2 5 s at t = 25.000 s)"
    )
    result = run_scenario(load_plant(None), wrong, check=False)
    assert not result["passed"] and result["done"]
    failed_ones = [o for o in result["outcomes"] if not o["ok"]]
    assert [(o["index"], o["what"], o["expected"], o["actual"], o["t_s"]) for o in failed_ones] == [
        (5, "tes2 LED Pwr", "'on'", "'off'", 26.0)
    ]


def test_every_step_kind_runs_and_is_checked(plant: Plant, tmp_path: Path) -> None:
    path = tmp_path / "all.toml"
    path.write_text(
        """
[[step]]
at_s = 1
write = { object = "W100", value = 30 }
[[step]]
at_s = 1
write = { device = "tes2", register = "0x000", value = 0 }
[[step]]
at_s = 1
[step.signal]
device = "tes2"
name = "a1"
kind = "ramp"
start = 0.0
end = 10.0
t0_s = 1
duration_s = 10
[[step]]
at_s = 1
input = { device = "5", name = "1", value = "12mA" }
[[step]]
at_s = 2
remove = { module = "14" }
[[step]]
at_s = 3
insert = { module = "14" }
[[step]]
at_s = 4
exchange = { m = 0x0563, c = 0x49, text = "TANK FARM", txt = 7 }
[[step]]
at_s = 5
power_off = { device = "plc", seconds = 0.5 }
[[step]]
at_s = 6
console = "write W101 7"

[[expect]]
at_s = 1.5
object = "W100"
equals = 30
[[expect]]
at_s = 1.5
device = "tes2"
register = "0x000"
equals = 0
[[expect]]
at_s = 6
device = "tes2"
input = "a1"
between = [4.9, 5.1]
[[expect]]
at_s = 2.5
device = "14"
led = "OK"
equals = "off"
[[expect]]
at_s = 6
object = "W101"
equals = 7
[[expect]]
at_s = 6
device = "16"
output = "0"
between = [0, 1]
"""
    )
    result = run_scenario(plant, path, check=False)
    assert result["passed"], result["failure"] or result["outcomes"]
    assert plant.clock.now == 6 * S


def test_a_step_the_plant_refuses_fails_the_scenario_naming_it(
    plant: Plant, tmp_path: Path
) -> None:
    path = tmp_path / "refused.toml"
    path.write_text(
        "[[step]]\nat_s = 1\nfault = { device = 'tes1', name = 'melted' }\n"
        "[[expect]]\nat_s = 2\nobject = 'W0'\nbetween = [0, 10000]\n"
    )
    result = run_scenario(plant, path, check=False)
    assert result["done"] and not result["passed"]
    assert result["failure"].startswith(
        "step[1] fault tes1 melted on at t = 1.000 s failed: unknown fault 'melted' for TES 32EST"
    )


def test_unknown_names_are_refused_before_anything_runs(plant: Plant, tmp_path: Path) -> None:
    path = tmp_path / "names.toml"
    path.write_text("[[expect]]\nat_s = 2\ndevice = 'tes9'\nled = 'Pwr'\nequals = 'on'\n")
    with pytest.raises(Exception, match=r"names\.toml: expect\[1\]\.led: device: no device 'tes9'"):
        run_scenario(plant, path)
    path.write_text("[[step]]\nat_s = 2\ninput = { device = 'x', name = '0', value = 1 }\n")
    with pytest.raises(Exception, match=r"step\[1\]\.input\.device: no device 'x' \(allowed: 4, 5"):
        run_scenario(plant, path)
    assert plant.clock.now == 0


def test_the_console_runs_a_scenario_from_now(plant: Plant) -> None:
    from fieldtwin.console import Console
    from fieldtwin.control.scenarios import fallback_handlers

    console = Console(plant)
    console.call = fallback_handlers(plant)["call"]
    console.execute("advance 10")
    lines = console.execute(f"scenario {EXAMPLES / 'scada_alarm.toml'}")
    assert lines[0] == "ok   t = 12.000 s  step[1]  write tes2 0x000 = 0"
    assert lines[-1] == (
        "scenario scada_alarm.toml: passed (4 steps, 5 expectations held, ended at t = 19.000 s)"
    )
    from fieldtwin.errors import ConfigError

    api_console = Console(plant, files=False)
    with pytest.raises(ConfigError, match=r"scenario: reads a file, not allowed here \(POST"):
        api_console.execute(f"scenario {EXAMPLES / 'scada_alarm.toml'}")
