"""The running_plant fixture in a fresh project: a real `fieldtwin run` on free ports,
polled with pymodbus; torn down after a pass, a failure, a KeyboardInterrupt and even
a killed test process; its output in the report of a failing test."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest

from tests.plugin.project import user_project, write

STATION = """\
[plant]
name = "pump station"

[[tes]]
model = "TES 32EST"
slave = 1
endpoint = "tcp://127.0.0.1:5020"
inputs = { 2 = true }

[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:5021"
inputs = { a0 = 5.0 }

[[tes]]
model = "TES 16EST"
slave = 3
endpoint = 'tcp://127.0.0.1:5020'

[[tes]]
model = "TES 32ST"
slave = 1
endpoint = "rtu+tcp://127.0.0.1:5023"

[[tes]]
model = "TES 4EA"
slave = 5
endpoint = "pty"
"""

STATION_TEST = """
import json, os
import pytest
from pymodbus.client import ModbusTcpClient
from fieldtwin.testing import assert_object

@pytest.mark.plant("plants/station.toml")
def test_station(running_plant, run_until):
    one, two = running_plant.modbus(1, declared="tcp://127.0.0.1:5020"), running_plant.modbus(2)
    assert one.what == "modbus-tcp" and one.slaves == (1, 3)
    assert two.slaves == (2,) and two.declared == "tcp://127.0.0.1:5021"
    assert one.port not in (0, 5020) and two.port not in (0, 5021, one.port)
    rtu = running_plant.modbus(1, declared="rtu+tcp://127.0.0.1:5023")
    assert rtu.what == "modbus-rtu-over-tcp" and rtu.port not in (0, 5023)
    pty = running_plant.modbus(5)
    assert pty.what == "modbus-rtu" and pty.url.startswith("/dev/")
    with pytest.raises(Exception, match="slave 1 answers on 2 endpoints"):
        running_plant.modbus(1)
    master = ModbusTcpClient(one.host, port=one.port, timeout=2, retries=0)
    assert master.connect()
    try:
        word = lambda: master.read_holding_registers(0x005, count=1, device_id=1).registers[0]
        assert word() & 0x4                                     # input 2, from the file
        running_plant.api.set_input("tes1", "6", True)
        assert run_until(lambda: word() & 0x40, within=5) == 0x40
        assert_object(running_plant, "tes1:0x005", 0x44)
        analog = ModbusTcpClient(two.host, port=two.port, timeout=2, retries=0)
        assert analog.connect()
        assert not analog.read_holding_registers(0, count=1, device_id=2).isError()
        analog.close()
    finally:
        master.close()
    with open(os.environ["RECORD"], "w") as f:
        json.dump({"pid": running_plant.pid, "copy": str(running_plant._copy)}, f)
"""


def alive(pid: int) -> bool:
    """Running (a zombie no parent reaps is not running)."""
    try:
        state = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in state and "\nState:\tX" not in state


def gone(pid: int, wait_s: float = 20.0) -> bool:
    deadline = time.monotonic() + wait_s
    while alive(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def record(pytester: pytest.Pytester) -> dict[str, object]:
    return dict(json.loads((pytester.path / "record.json").read_text()))


@pytest.fixture()
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    user_project(pytester)
    write(pytester, "plants/station.toml", STATION)
    monkeypatch.setenv("RECORD", str(pytester.path / "record.json"))
    return pytester


def test_free_ports_for_every_endpoint_and_torn_down_after(project: pytest.Pytester) -> None:
    write(project, "tests/test_station.py", STATION_TEST)
    result = project.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1)
    seen = record(project)
    assert isinstance(seen["pid"], int) and gone(seen["pid"])
    assert not Path(str(seen["copy"])).exists()
    assert sorted(p.name for p in (project.path / "plants").iterdir()) == ["station.toml"]
    assert "fieldtwin run (call)" not in result.stdout.str()  # a pass shows no output


def test_a_failing_test_shows_the_run_output(project: pytest.Pytester) -> None:
    write(
        project,
        "tests/test_fail.py",
        """
import json, os
import pytest

@pytest.mark.plant("plants/station.toml", speed=2)
def test_fails(running_plant):
    with open(os.environ["RECORD"], "w") as f:
        json.dump({"pid": running_plant.pid, "copy": str(running_plant._copy)}, f)
    running_plant.api.console("advance 1")
    assert running_plant.api.clock()["speed"] == 2.0
    assert False, "the poller saw nothing"
""",
    )
    result = project.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "*AssertionError: the poller saw nothing*",
            "*- fieldtwin run (call) -*",
            "$ fieldtwin run */plants/.station.fieldtwin-*.toml --no-live --control-port 0"
            " --speed 2",
            "# .station.fieldtwin-*.toml: */plants/station.toml with its TCP endpoints on free"
            " ports",
            "--- stdout ---",
            "listening: modbus-tcp tcp://127.0.0.1:* slaves 1,3",
            "listening: modbus-tcp tcp://127.0.0.1:* slaves 2",
            "listening: modbus-rtu-over-tcp rtu+tcp://127.0.0.1:* slaves 1 (38400 8E1)",
            "listening: modbus-rtu pty /dev/* slaves 5 (38400 8E1)",
            "running pump station at x2",
            "control: http://127.0.0.1:*",
            "--- stderr ---",
        ]
    )
    seen = record(project)
    assert isinstance(seen["pid"], int) and gone(seen["pid"])
    assert not Path(str(seen["copy"])).exists()


def test_keyboard_interrupt_stops_the_run(project: pytest.Pytester) -> None:
    write(
        project,
        "tests/test_interrupt.py",
        """
import json, os

def test_interrupted(running_plant):
    with open(os.environ["RECORD"], "w") as f:
        json.dump({"pid": running_plant.pid, "copy": str(running_plant._copy)}, f)
    raise KeyboardInterrupt

def test_never_runs():
    pass
""",
    )
    result = project.runpytest_subprocess("-p", "no:cacheprovider")
    assert result.ret == pytest.ExitCode.INTERRUPTED
    seen = record(project)
    assert isinstance(seen["pid"], int) and gone(seen["pid"])
    assert not Path(str(seen["copy"])).exists()


def test_a_killed_test_process_takes_the_run_with_it(project: pytest.Pytester) -> None:
    write(
        project,
        "tests/test_killed.py",
        """
import json, os, signal
import pytest

@pytest.mark.plant("plants/station.toml")
def test_killed(running_plant):
    with open(os.environ["RECORD"], "w") as f:
        json.dump({"pid": running_plant.pid}, f)
    os.kill(os.getpid(), signal.SIGKILL)      # no teardown, no atexit
""",
    )
    result = project.runpytest_subprocess("-p", "no:cacheprovider")
    assert result.ret == -signal.SIGKILL
    seen = record(project)
    assert isinstance(seen["pid"], int) and gone(seen["pid"])
    stale = [p.name for p in (project.path / "plants").iterdir() if p.name != "station.toml"]
    assert len(stale) == 1 and stale[0].startswith(".station.fieldtwin-")
    # the next run of that plant file removes the copy the killed process left
    (project.path / "tests" / "test_killed.py").unlink()
    write(project, "tests/test_station.py", STATION_TEST)
    project.runpytest_subprocess("-p", "no:cacheprovider").assert_outcomes(passed=1)
    assert sorted(p.name for p in (project.path / "plants").iterdir()) == ["station.toml"]


def test_a_plant_the_run_refuses_is_a_setup_error_with_its_output(
    project: pytest.Pytester,
) -> None:
    write(
        project,
        "plants/clash.toml",
        STATION + '\n[[tes]]\nmodel = "TES 8EA"\nslave = 2\n'
        'endpoint = "tcp://127.0.0.1:5020"\nlink = "rs232"\n',
    )
    write(
        project,
        "tests/test_refused.py",
        """
import pytest

@pytest.mark.plant("plants/clash.toml")
def test_refused(running_plant):
    pass
""",
    )
    result = project.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(
        [
            "*running_plant fixture: fieldtwin run */plants/clash.toml ended with status 2"
            " before it was ready",
            "--- stderr ---",
            "fieldtwin: *",
        ]
    )
    assert sorted(p.name for p in (project.path / "plants").iterdir()) == [
        "clash.toml",
        "station.toml",
    ]


def test_start_plant_without_pytest(tmp_path: Path) -> None:
    from fieldtwin.testing import start_plant

    (tmp_path / "p.toml").write_text(STATION)
    with start_plant(tmp_path / "p.toml", speed=1) as running:
        pid = running.pid
        assert running.alive() and running.url.startswith("http://127.0.0.1:")
        assert running.api.plant()["title"] == "pump station"
        target = running.now_s() + 0.5
        running.advance_to(target)
        assert running.now_s() >= target
        with pytest.raises(AssertionError, match=r"cannot advance to t = 0.25 s: simulated time"):
            running.advance_to(0.25)
    assert pid is not None and gone(pid)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.toml"]
    assert os.environ.get("FIELDTWIN_TEST_PARENT") is None


def test_the_default_plant_runs_with_its_channels_and_its_modbus_endpoint() -> None:
    from fieldtwin.testing import assert_leds, assert_object, assert_state, start_plant

    with start_plant() as running:
        tes = running.modbus(2)
        assert tes.slaves == (1, 2) and tes.declared == "tcp://127.0.0.1:5020"
        assert tes.port not in (0, 5020)
        channel = running.channel("7", 1)
        assert channel.what == "TSX SCM 2111 slot 7 channel 1" and channel.url.startswith("/dev/")
        with pytest.raises(Exception, match=r"no endpoint for slot 7 channel 2 \(have: "):
            running.channel("7", 2)
        assert_state(running, "on", device="tes1")
        assert_leds(running, {"Pwr": "on"}, device="tes1")
        assert_object(running, "OW4,2", 0x000F)  # a PLC object, through the console
        with pytest.raises(
            AssertionError,
            match=r"OW4,2 of running plant \(the default plant\):"
            r" expected 1, actual 15 \(H'000F'\) at t = ",
        ):
            assert_object(running, "OW4,2", 1)
        with pytest.raises(AssertionError) as caught:
            running.run_until(lambda: False, within=0.3, show=["tes1:0x000"])
        assert "not true within 0.3 s" in str(caught.value)
        assert "tes1:0x000 = " in str(caught.value)
