"""Black box: the real `fieldtwin run --trace --pcap`, a pymodbus master, tshark, trace show."""

from __future__ import annotations

import json
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.systools import require

ROOT = Path(__file__).resolve().parents[2]
PLANT = """
[plant]
name = "trace test"

[[tes]]
model = "TES 32EST"
slave = 1
endpoint = "tcp://127.0.0.1:0"

[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:0"
faults = ["no_answer"]

[[tes]]
model = "TES 32EST"
slave = 3
endpoint = "rtu+tcp://127.0.0.1:0"
"""


def _ports(proc: subprocess.Popen[str]) -> tuple[int, int]:
    assert proc.stdout is not None
    tcp = rtu = None
    deadline = time.monotonic() + 20
    # the two lines come together: select once for the first, then read the buffered rest
    while (tcp is None or rtu is None) and time.monotonic() < deadline:
        if tcp is not None or rtu is not None or select.select([proc.stdout], [], [], 0.5)[0]:
            line = proc.stdout.readline()
            if not line:
                break
            if m := re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves 1,2", line):
                tcp = int(m.group(1))
            if m := re.match(r"listening: modbus-rtu-over-tcp rtu\+tcp://127\.0\.0\.1:(\d+)", line):
                rtu = int(m.group(1))
    assert tcp is not None and rtu is not None, "the endpoints were not announced"
    return tcp, rtu


def _poll(tcp: int, rtu: int) -> None:
    from pymodbus.client import ModbusTcpClient
    from pymodbus.exceptions import ModbusIOException
    from pymodbus.framer import FramerType

    client = ModbusTcpClient("127.0.0.1", port=tcp, timeout=0.5, retries=0)
    assert client.connect()  # type: ignore[no-untyped-call]
    try:
        assert not client.read_holding_registers(0, count=2, device_id=1).isError()
        with pytest.raises(ModbusIOException):  # TES 2 has no_answer: silence
            client.read_holding_registers(0, count=2, device_id=2)
        assert not client.write_register(0x100, 1, device_id=1).isError()
        assert not client.read_coils(0, count=4, device_id=1).isError()
    finally:
        client.close()  # type: ignore[no-untyped-call]
    client = ModbusTcpClient("127.0.0.1", port=rtu, timeout=0.5, retries=0, framer=FramerType.RTU)
    assert client.connect()  # type: ignore[no-untyped-call]
    try:
        assert not client.read_holding_registers(0, count=2, device_id=3).isError()
    finally:
        client.close()  # type: ignore[no-untyped-call]


@pytest.fixture(scope="module")
def traced(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, int, int]:
    tmp = tmp_path_factory.mktemp("trace")
    plant, trace, pcap = tmp / "plant.toml", tmp / "t.jsonl", tmp / "t.pcap"
    plant.write_text(PLANT)
    argv = [
        "run",
        str(plant),
        "--no-live",
        "--no-control",
        "--trace",
        str(trace),
        "--pcap",
        str(pcap),
    ]
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    try:
        tcp, rtu = _ports(proc)
        _poll(tcp, rtu)
    finally:
        proc.terminate()
        try:
            _, err = proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate(timeout=5)
            raise
    assert proc.returncode == 0, err
    return trace, pcap, tcp, rtu


def test_the_trace_says_who_answered_and_who_did_not(traced: tuple[Path, Path, int, int]) -> None:
    trace = traced[0]
    records = [json.loads(line) for line in trace.read_text().splitlines()]
    frames = [r for r in records if r["kind"] == "modbus"]
    to_2 = [r for r in frames if r["slave"] == 2]
    assert [r["dir"] for r in to_2] == ["in"]  # asked, never answered
    assert to_2[0]["tes"] == {"TES 32EST #1": "not_addressed", "TES 8EA #2": "no_answer"}
    assert to_2[0]["function"] == 3 and to_2[0]["address"] == 0 and to_2[0]["count"] == 2
    to_1 = [(r["dir"], r["function"]) for r in frames if r["slave"] == 1]
    assert to_1 == [("in", 3), ("out", 3), ("in", 6), ("out", 6), ("in", 1), ("out", 1)]
    answered = [r for r in frames if r["slave"] == 1 and r["dir"] == "out"]
    assert {r["from"] for r in answered} == {"TES 32EST #1"}
    rtu = [r for r in frames if r["transport"] == "rtu+tcp"]
    assert [(r["dir"], r["crc"], r["slave"]) for r in rtu] == [
        ("in", "good", 3),
        ("out", "good", 3),
    ]
    for r in frames:
        assert isinstance(r["t"], float) and r["wall"] > 1e9
        assert r["endpoint"] in ("tcp://127.0.0.1:0", "rtu+tcp://127.0.0.1:0")


def test_tshark_decodes_the_pcap_as_modbus(traced: tuple[Path, Path, int, int]) -> None:
    _, pcap, tcp, rtu = traced
    tshark = require("tshark")  # skipped with one summary line when missing (not in CI)
    argv = [tshark, "-r", str(pcap), "-d", f"tcp.port=={tcp},mbtcp", "-d", f"tcp.port=={rtu},mbrtu"]
    fields = [
        "-T",
        "fields",
        "-e",
        "mbtcp.trans_id",
        "-e",
        "mbrtu.unit_id",
        "-e",
        "modbus.func_code",
    ]
    done = subprocess.run(
        [*argv, "-Y", "modbus", *fields], capture_output=True, text=True, timeout=60, check=True
    )
    rows = [line.split("\t") for line in done.stdout.splitlines()]
    mbtcp = [(row[0], row[2]) for row in rows if row[0]]
    assert mbtcp == [
        ("1", "3"),
        ("1", "3"),
        ("2", "3"),
        ("3", "6"),
        ("3", "6"),
        ("4", "1"),
        ("4", "1"),
    ]
    assert [(row[1], row[2]) for row in rows if row[1]] == [("3", "3"), ("3", "3")]
    # -o mbtcp.tcp.port:PORT also tells queries from responses (docs/trace.md)
    done = subprocess.run(
        [tshark, "-r", str(pcap), "-o", f"mbtcp.tcp.port:{tcp}", "-Y", "mbtcp"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert done.stdout.count("Query") == 4 and done.stdout.count("Response") == 3


def test_trace_show_prints_it_with_filters(traced: tuple[Path, Path, int, int]) -> None:
    trace = traced[0]

    def show(*args: str) -> list[str]:
        done = subprocess.run(
            [sys.executable, "-m", "fieldtwin", "trace", "show", str(trace), *args],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=ROOT,
            check=True,
        )
        return done.stdout.splitlines()

    lines = show()
    assert len(lines) == 9
    assert "in   slave 2  read_holding_registers  addr 0 count 2" in lines[2]
    assert lines[2].endswith("TES 32EST #1 not_addressed; TES 8EA #2 no_answer")
    # the reply's values follow its outcome (trace show prints the values read)
    assert "from TES 32EST #1: ok  read H'" in lines[1]
    assert len(show("--slave", "2")) == 1
    assert len(show("--function", "write_single_register")) == 2
    assert len(show("--function", "6")) == 2
    assert len(show("--endpoint", "rtu+tcp://127.0.0.1:0")) == 2


def test_trace_show_names_a_bad_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"t": 1.0, "kind": "modbus"}\nnot json\n')
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "trace", "show", str(bad)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 2
    assert f"{bad} line 2: not a trace line" in done.stderr
    assert "Traceback" not in done.stderr
