"""Scenarios as a user runs them: `fieldtwin run --scenario` (a real subprocess, its exit
status and message), ``POST /scenarios`` and ``run_scenario`` on a running plant."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from fieldtwin.client import Client, ControlError
from fieldtwin.testing import RunningPlant, run_scenario, start_plant
from tests.control.plantproc import ROOT, default_plant_copy

EXAMPLES = ROOT / "examples" / "scenarios"
WALL_S = 120


def fieldtwin_run(plant: Path, scenario: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            *(sys.executable, "-m", "fieldtwin", "run", str(plant), "--scenario", str(scenario)),
            *("--speed", "max", "--no-live", "--control-port", "0", *extra),
        ],
        capture_output=True,
        text=True,
        timeout=WALL_S,
        cwd=ROOT,
    )


def test_the_fault_drill_passes_exit_0(tmp_path: Path) -> None:
    done = fieldtwin_run(default_plant_copy(tmp_path), EXAMPLES / "fault_drill.toml")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "stopped at t = 40.000 s" in done.stdout
    assert "ok   t = 25.000 s  step[2]  power_off tes2 5 s" in done.stdout
    assert (
        "scenario fault_drill.toml: passed (3 steps, 8 expectations held, ended at t = 40.000 s)"
        in done.stdout
    )


def test_a_wrong_expectation_exits_1_naming_step_object_values_and_time(tmp_path: Path) -> None:
    wrong = tmp_path / "wrong.toml"
    text = (EXAMPLES / "fault_drill.toml").read_text()
    wrong.write_text(
        text.replace('object = "IW5,0,3"\nequals = 1', 'object = "IW5,0,3"\nequals = 0')
    )
    done = fieldtwin_run(default_plant_copy(tmp_path), wrong, "--no-control")
    assert done.returncode == 1, done.stdout + done.stderr
    message = (
        "expect[3] at t = 24.000 s: IW5,0,3 expected 0, actual 1"
        " (after step[1] fault 5 open_3 on at t = 20.000 s)"
    )
    assert f"fieldtwin: scenario wrong.toml: FAILED: {message}" in done.stderr
    assert f"FAIL {message}" in done.stdout
    assert "stopped at t = 40.000 s" in done.stdout  # it ran to its end all the same


def test_a_bad_scenario_file_exits_2_before_the_plant_starts(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[[step]]\nat_s = 1\npower_off = { device = 'tes2', seconds = 9999 }\n")
    done = fieldtwin_run(default_plant_copy(tmp_path), bad)
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "fieldtwin: bad.toml: step[1].power_off.seconds: 9999 not allowed (allowed: 0 to 3600)"
    )
    assert "running" not in done.stdout


@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningPlant]:
    plant = default_plant_copy(tmp_path_factory.mktemp("scenarios"))
    with start_plant(plant, speed=10) as run:
        yield run


def test_run_scenario_on_a_running_plant_through_post_scenarios(running: RunningPlant) -> None:
    result = run_scenario(running, EXAMPLES / "scada_alarm.toml", wall_s=60)
    assert result["passed"] and result["done"] and result["id"] >= 1
    assert result["started_s"] > 0  # from the running plant's time when it was started
    with Client(running.api.url) as api:
        listed = api.request("GET", "/scenarios")
        assert {
            "id": result["id"],
            "name": "scada_alarm.toml",
            "done": True,
            "passed": True,
        } in listed
        again = api.request("GET", f"/scenarios/{result['id']}")
        assert [o["what"] for o in again["outcomes"]][:2] == [
            "write tes2 0x000 = 0",
            "tes2 register 0x000",
        ]


def test_post_scenarios_refuses_a_bad_text_naming_the_field(running: RunningPlant) -> None:
    with Client(running.api.url) as api:
        with pytest.raises(ControlError) as bad:
            api.request(
                "POST",
                "/scenarios",
                {"text": "[[expect]]\nat_s = 1\nobject = 'W0'\n", "name": "mine.toml"},
            )
        assert bad.value.status == 409
        assert "mine.toml: expect[1]: give either equals or between" in str(bad.value)
        with pytest.raises(ControlError) as missing:
            api.request("GET", "/scenarios/9999")
        assert missing.value.status == 404
