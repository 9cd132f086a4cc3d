"""One `fieldtwin run` process serving TES on Modbus TCP and on two pty lines.

The plant (written in a temporary directory) holds one TES of each of the ten
models for the table-driven memory-map tests (slaves 1..10, spread over TCP
and line A) and more TES with input signals for the behaviour tests.  The
process runs paced at ``SPEED`` times the wall clock; the tests talk to it with
the pymodbus client only (and raw bytes on a pty for broken frames).  Every
wait is bounded; teardown terminates the process and checks it exits 0.
"""

from __future__ import annotations

import os
import re
import select
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.pdu import ExceptionResponse, ModbusPDU

from fieldtwin.tes import Tes

SPEED = 20  # simulated seconds per wall second
START_S = 15.0  # wall bound for the process to print its endpoints
STOP_S = 10.0  # wall bound for the process to exit after SIGTERM
IO_TIMEOUT_S = 1.0  # pymodbus client timeout (no retries)

ROOT = Path(__file__).resolve().parents[3]

# slave -> (model, endpoint key, extra TOML); the ten map TES are slaves 1..10.
MAP_TES = {
    1: "TES 16EST",
    2: "TES 32EST",
    3: "TES 32ET",
    4: "TES 4EA",
    5: "TES 8EA",
    6: "TES 32ET-S",
    7: "TES 32ST",
    8: "TES 4SA",
    9: "TES 8ESA",
    10: "TES 8SA-U",
}
TCP, LINE_A, LINE_B = "tcp://127.0.0.1:0", "pty", "pty?baud=38400&parity=E"
MAP_ENDPOINT = {s: TCP if s <= 5 else LINE_A for s in MAP_TES}

# behaviour TES
CLOCKS = 20  # 16EST: pulse trains on inputs 0 (1 s) and 2 (0.1 s); input 7 stays 0
MEMORIZED = 21  # 16EST on line A: input 1 changes 5 times between 1.0 and 1.5 s
WATCHDOG = 22  # 32EST: master watching and fallback
ANALOG = 23  # 8EA: constant, ramp, scaled, filtered and threshold channels
NOT_READY = 24  # 32ET with a 50 ms "slave not ready" window every 100 ms
SAFETY = 25  # 32ET-S: input 3 short-circuited, input 7 wire broken
ANALOG_WDG = 26  # 4SA on line A: analog fallback
LINE_B_SLAVES = (31, 32, 33)  # 16EST, 32EST, 16EST sharing line B

BEHAVIOUR = f"""
[[tes]]
model = "TES 16EST"
slave = {CLOCKS}
endpoint = "{TCP}"
inputs.0 = {{ kind = "pulse", period_s = 1.0 }}
inputs.2 = {{ kind = "pulse", period_s = 0.1 }}
inputs.7 = false

[[tes]]
model = "TES 16EST"
slave = {MEMORIZED}
endpoint = "{LINE_A}"
inputs = {{ 1 = {{ kind = "edges", times_s = [1.0, 1.1, 1.2, 1.3, 1.5] }} }}

[[tes]]
model = "TES 32EST"
slave = {WATCHDOG}
endpoint = "{TCP}"

[[tes]]
model = "TES 8EA"
slave = {ANALOG}
endpoint = "{TCP}"
name = "ana"
store = "eeprom.db"
inputs.a0 = 5.0
inputs.a1 = {{ kind = "ramp", start = 0.0, end = 10.0, duration_s = 100 }}
inputs.a2 = 10.0
inputs.a3 = {{ kind = "square", low = 0.0, high = 10.0, period_s = 1.0 }}
inputs.a4 = {{ kind = "square", low = 0.0, high = 10.0, period_s = 1.0 }}
inputs.a5 = {{ kind = "sine", offset = 5.0, amplitude = 5.0, period_s = 4.0 }}
inputs.a6 = {{ kind = "sine", offset = 5.0, amplitude = 5.0, period_s = 4.0 }}
inputs.a7 = {{ kind = "sine", offset = 5.0, amplitude = 5.0, period_s = 4.0 }}

[[tes]]
model = "TES 32ET"
slave = {NOT_READY}
endpoint = "{TCP}"
faults = {{ not_ready_ms = 50 }}

[[tes]]
model = "TES 32ET-S"
slave = {SAFETY}
endpoint = "{TCP}"
faults = {{ short = [3], open = [7] }}

[[tes]]
model = "TES 4SA"
slave = {ANALOG_WDG}
endpoint = "{LINE_A}"

[[tes]]
model = "TES 16EST"
slave = 31
endpoint = "{LINE_B}"
inputs = {{ 0 = {{ kind = "pulse", period_s = 0.2 }} }}

[[tes]]
model = "TES 32EST"
slave = 32
endpoint = "{LINE_B}"
inputs = {{ 0 = {{ kind = "pulse", period_s = 0.3 }} }}

[[tes]]
model = "TES 16EST"
slave = 33
endpoint = "{LINE_B}"
inputs = {{ 0 = {{ kind = "pulse", period_s = 0.5 }} }}
"""

# EEPROM of the ANALOG TES, written the way TESIS would (§4.2.3, §4.2.4).
ANALOG_EEPROM = {
    "ai2.scale": "on",
    "ai2.scale_min": -100,
    "ai2.scale_max": 15000,
    "ai3.filter": 256,
}


def plant_text() -> str:
    tables = [
        f'[[tes]]\nmodel = "{model}"\nslave = {slave}\nendpoint = "{MAP_ENDPOINT[slave]}"\n'
        for slave, model in MAP_TES.items()
    ]
    return '[plant]\ntitle = "tes black box"\n\n' + "\n".join(tables) + BEHAVIOUR


@dataclass
class Running:
    proc: subprocess.Popen[bytes]
    tcp_port: int
    line_a: str
    line_b: str
    lines: list[str]


def _read_lines(proc: subprocess.Popen[bytes], until: str, deadline: float) -> list[str]:
    """stdout lines up to and including one starting with ``until`` (select-bounded)."""
    assert proc.stdout is not None
    fd = proc.stdout.fileno()
    buffer, lines = b"", []
    while time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            break
        chunk = os.read(fd, 4096)
        if not chunk:
            break
        buffer += chunk
        while b"\n" in buffer:
            line, buffer = buffer.split(b"\n", 1)
            lines.append(line.decode())
            if lines[-1].startswith(until):
                return lines
    raise AssertionError(f"no {until!r} line within the bound; got {lines!r}")


def _endpoints(lines: list[str]) -> tuple[int, str, str]:
    port, ptys = 0, {}
    for line in lines:
        tcp = re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves ", line)
        pty = re.match(r"listening: modbus-rtu pty (\S+) slaves ([\d,]+)", line)
        if tcp:
            port = int(tcp.group(1))
        elif pty:
            ptys[pty.group(2)] = pty.group(1)
    line_b = ptys.pop(",".join(map(str, LINE_B_SLAVES)))
    (line_a,) = ptys.values()
    assert port
    return port, line_a, line_b


def _prepare_store(directory: Path) -> None:
    # setup, not the device under test: the EEPROM a TESIS download leaves
    Tes("TES 8EA", ANALOG, store=directory / "eeprom.db", name="ana").write_eeprom(ANALOG_EEPROM)


def start_plant(
    directory: Path, text: str, speed: float
) -> tuple[subprocess.Popen[bytes], list[str]]:
    """`fieldtwin run` on a plant file written in ``directory``; its lines up to ``running``."""
    plant = directory / "plant.toml"
    plant.write_text(text)
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "run", str(plant), "--no-live", "--speed", str(speed)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=ROOT,
    )
    try:
        return proc, _read_lines(proc, "running ", time.monotonic() + START_S)
    except BaseException:
        proc.kill()
        proc.communicate(timeout=STOP_S)
        raise


def stop_plant(proc: subprocess.Popen[bytes]) -> None:
    """SIGTERM, a bounded wait, and the process must exit 0 with its last line."""
    proc.terminate()
    try:
        out, err = proc.communicate(timeout=STOP_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate(timeout=STOP_S)
        raise AssertionError("fieldtwin run did not stop after SIGTERM") from None
    assert proc.returncode == 0, err.decode()
    assert out.decode().splitlines()[-1].startswith("stopped at t = ")


@pytest.fixture(scope="session")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    directory = tmp_path_factory.mktemp("tes_blackbox")
    _prepare_store(directory)
    proc, lines = start_plant(directory, plant_text(), SPEED)
    try:
        yield Running(proc, *_endpoints(lines), lines)
    finally:
        stop_plant(proc)


@pytest.fixture(scope="session")
def tcp(running: Running) -> Iterator[ModbusTcpClient]:
    client = ModbusTcpClient("127.0.0.1", port=running.tcp_port, timeout=IO_TIMEOUT_S, retries=0)
    assert client.connect()  # type: ignore[no-untyped-call]
    yield client
    client.close()  # type: ignore[no-untyped-call]


def _serial(path: str) -> ModbusSerialClient:
    # Linux ptys refuse parity settings: the master opens the line 8N1 (docs/modbus.md)
    client = ModbusSerialClient(
        path, baudrate=38400, bytesize=8, parity="N", stopbits=1, timeout=IO_TIMEOUT_S, retries=0
    )
    assert client.connect()
    return client


@pytest.fixture(scope="session")
def line_a(running: Running) -> Iterator[ModbusSerialClient]:
    client = _serial(running.line_a)
    yield client
    client.close()  # type: ignore[no-untyped-call]


@pytest.fixture(scope="session")
def line_b(running: Running) -> Iterator[ModbusSerialClient]:
    client = _serial(running.line_b)
    yield client
    client.close()  # type: ignore[no-untyped-call]


Client = ModbusTcpClient | ModbusSerialClient


def client_for(slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient) -> Client:
    return tcp if MAP_ENDPOINT.get(slave, TCP) == TCP else line_a


def words(client: Client, slave: int, address: int, count: int = 1) -> list[int]:
    reply = client.read_holding_registers(address, count=count, device_id=slave)
    assert not reply.isError(), (slave, hex(address), count, reply)
    return list(reply.registers)


def write(client: Client, slave: int, address: int, *values: int) -> None:
    if len(values) == 1:
        reply = client.write_register(address, values[0], device_id=slave)
    else:
        reply = client.write_registers(address, list(values), device_id=slave)
    assert not reply.isError(), (slave, hex(address), values, reply)


def exception_code(reply: ModbusPDU) -> int:
    assert isinstance(reply, ExceptionResponse), reply
    return int(reply.exception_code)


def pair(hi: int, lo: int) -> int:
    return hi << 16 | lo


def sim_ticks(tcp: ModbusTcpClient) -> int:
    """Simulated time since power-on in 100 ms ticks: input 7 of CLOCKS stays 0 (§6.2.6.2)."""
    return pair(*words(tcp, CLOCKS, 0x165 + 2 * 7, 2))


def wait_sim(tcp: ModbusTcpClient, seconds: float) -> int:
    """Wait (bounded) until the plant's simulated time has reached ``seconds``."""
    deadline = time.monotonic() + seconds / SPEED * 3 + 5
    while (ticks := sim_ticks(tcp)) < seconds * 10:
        assert time.monotonic() < deadline, f"simulated time stuck at {ticks / 10} s"
        time.sleep(0.02)
    return ticks
