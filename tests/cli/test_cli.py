"""The real `fieldtwin` command, run as a user runs it (subprocess)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def fieldtwin(
    *args: str, stdin: str | None = None, timeout: float = 60
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *args],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        check=False,
    )


def default_plant_copy(tmp_path: Path) -> Path:
    """The embedded default plant with its Modbus TCP port left to the system (port 0)."""
    from importlib import resources

    text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text("utf-8")
    assert "tcp://127.0.0.1:5020" in text
    path = tmp_path / "default.toml"
    path.write_text(text.replace("tcp://127.0.0.1:5020", "tcp://127.0.0.1:0"))
    return path


def plc_plant(tmp_path: Path) -> Path:
    path = tmp_path / "plc.toml"
    path.write_text('[plc]\nmodel = "TSX 47-20"\nscan_ms = 10\n')
    return path


def test_console_script_from_a_file(tmp_path: Path) -> None:
    script = tmp_path / "s.txt"
    script.write_text("# set a word\nwrite W10 H'00A0'\nread W10\nadvance 1.5s\ntime\n")
    done = fieldtwin("console", str(plc_plant(tmp_path)), "--script", str(script))
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["W10 = 160", "W10 = 160", "t = 1.500 s", "t = 1.500 s"]


def test_console_script_error_exits_2_naming_the_line(tmp_path: Path) -> None:
    done = fieldtwin("console", str(plc_plant(tmp_path)), stdin="time\nread IW5,X\ntime\n")
    assert done.returncode == 2
    assert done.stdout.splitlines() == ["t = 0.000 s"]
    assert done.stderr.startswith("<stdin>:2: read IW5,X: 'IW5,X'")


def test_console_commands_on_the_command_line(tmp_path: Path) -> None:
    done = fieldtwin("console", str(plc_plant(tmp_path)), "-c", "advance 2min", "-c", "help time")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "t = 120.000 s"


def test_bad_plant_file_is_reported_with_status_2(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('[plc]\nmodel = "TSX 99"\n')
    done = fieldtwin("console", str(path), "-c", "time")
    assert done.returncode == 2
    assert "bad.toml: plc.model: 'TSX 99' not allowed" in done.stderr


def test_run_for_a_bounded_time_and_stop(tmp_path: Path) -> None:
    done = fieldtwin(
        "run",
        str(plc_plant(tmp_path)),
        "--speed",
        "max",
        "--duration",
        "5",
        "--no-live",
        "--status-every",
        "2",
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("running plc at max speed")
    assert lines[-1].startswith("stopped at t = 5.")
    assert sum(line.startswith("t = ") for line in lines) >= 2


def test_default_plant_runs_the_tank_application(tmp_path: Path) -> None:
    # the embedded plant on free ports (a plant already running holds 5020 and 8520)
    done = fieldtwin(
        "run",
        str(default_plant_copy(tmp_path)),
        "--control-port",
        "0",
        "--speed",
        "max",
        "--duration",
        "12",
        "--no-live",
        "--status-every",
        "11",
    )
    assert done.returncode == 0, done.stderr
    assert "slot 5 TSX AEM 811: Run OK=on ERR=off F=off IW H'1008'" in done.stdout


def test_default_plant_in_the_console() -> None:
    done = fieldtwin("console", "-c", "advance 12", "-c", "read IW5,0,C IW5,2,D", "-c", "status 5")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[:3] == ["t = 12.000 s", "IW5,0,C = 1", "IW5,2,D = 0"]
    assert "leds: OK=on ERR=off F=off" in lines


def test_run_serves_the_scm_on_a_pty_that_a_peer_types_into(tmp_path: Path) -> None:
    """`fieldtwin run` in real time; a pyserial peer types into the full-duplex channel."""
    import re
    import select
    import time

    import serial

    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "run",
            str(default_plant_copy(tmp_path)),
            "--no-live",
            "--status-every",
            "0.2",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    assert proc.stdout is not None
    try:
        paths: dict[str, str] = {}
        deadline = time.monotonic() + 30
        seen = ""
        peer = None
        while time.monotonic() < deadline:
            ready, _, _ = select.select([proc.stdout], [], [], 0.5)
            if not ready:
                continue
            line = proc.stdout.readline()
            seen += line
            match = re.match(r"listening: TSX SCM 2111 slot 7 channel (\d) pty (\S+)", line)
            if match:
                paths[match.group(1)] = match.group(2)
            if peer is None and "running" in line:
                assert set(paths) == {"0", "1"}, seen
                peer = serial.Serial(paths["1"], baudrate=9600, timeout=1)
            if peer is not None and "TSX SCM 2111: operational" in line and "typed" not in seen:
                peer.write(b"OK")
                seen += "typed\n"
            if "typed" in seen and re.search(r"SCM 2111: .* IW \S+ \S+ \S+ H'004B' H'0002'", line):
                break
        else:
            raise AssertionError(f"the typed characters never showed in IW7,3/IW7,4:\n{seen}")
        if peer is not None:
            peer.close()
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    assert proc.returncode == 0


def test_default_plant_serves_its_two_tes_to_a_modbus_master(tmp_path: Path) -> None:
    import re
    import select
    import time

    from pymodbus.client import ModbusTcpClient

    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "run", str(default_plant_copy(tmp_path)), "--no-live"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    assert proc.stdout is not None
    try:
        port = None
        deadline = time.monotonic() + 20
        while port is None and time.monotonic() < deadline:
            if select.select([proc.stdout], [], [], 0.5)[0]:
                match = re.match(
                    r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves 1,2",
                    proc.stdout.readline(),
                )
                port = int(match.group(1)) if match else None
        assert port is not None, "no Modbus TCP endpoint announced"
        client = ModbusTcpClient("127.0.0.1", port=port, timeout=2, retries=0)
        assert client.connect()  # type: ignore[no-untyped-call]
        try:
            for slave in (1, 2):
                reply = client.read_holding_registers(0, count=2, device_id=slave)
                assert not reply.isError(), reply
                assert len(reply.registers) == 2
            assert client.read_holding_registers(0, count=1, device_id=9).isError()
        finally:
            client.close()  # type: ignore[no-untyped-call]
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    assert proc.returncode == 0


def test_tesis_workbench_with_its_own_options(tmp_path: Path) -> None:
    store = str(tmp_path / "ee.db")
    base = ["tesis", "--store", store, "--model", "TES 8EA", "--device", "boiler"]
    done = fieldtwin(*base, "set", "ai0.filter", "16")
    assert done.returncode == 0, done.stderr
    shown = fieldtwin(*base, "show")
    assert shown.returncode == 0, shown.stderr
    assert "ai0.filter" in shown.stdout and "16" in shown.stdout
    refused = fieldtwin(*base, "set", "ai0.filter", "1000")
    assert refused.returncode == 2
    assert "ai0.filter" in refused.stderr + refused.stdout
    assert fieldtwin("tesis", "models").returncode == 0
