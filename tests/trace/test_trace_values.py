"""`fieldtwin trace show` prints the values a frame carries: what a write request
writes, what the reply to a read reads, in hex words or bits, bounded per line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from fieldtwin.tracecli import VALUES_SHOWN, frame_values, show_line


def tcp(direction: str, pdu: str, count: int, **extra: object) -> dict[str, object]:
    length = len(pdu) // 2 + 1
    return {
        "t": 1.0,
        "kind": "modbus",
        "endpoint": "tcp://127.0.0.1:0",
        "transport": "tcp",
        "dir": direction,
        "slave": 1,
        "hex": f"00070000{length:04x}01{pdu}",
        "function": int(pdu[:2], 16) & 0x7F,
        "function_name": "x",
        "address": 0,
        "count": count,
        **extra,
    }


def rtu(direction: str, pdu: str, count: int) -> dict[str, object]:
    record = tcp(direction, pdu, count)
    record["transport"] = "rtu"
    record["hex"] = f"05{pdu}abcd"  # the CRC is not read here: the trace checked it
    return record


@pytest.mark.parametrize(
    ("record", "shown"),
    [
        (tcp("out", "03040009ff00", 2), "read H'0009' H'FF00'"),
        (tcp("out", "0402002a", 1), "read H'002A'"),
        (rtu("out", "03040009ff00", 2), "read H'0009' H'FF00'"),
        (tcp("out", "01020581", 10), "read 1 0 1 0 0 0 0 0 1 0"),
        (tcp("out", "020105", 3), "read 1 0 1"),
        (tcp("out", "0705", 0), "read status H'05'"),
        (tcp("in", "060100abcd", 1), "write H'ABCD'"),
        (tcp("in", "050003ff00", 1), "write 1"),
        (rtu("in", "0500030000", 1), "write 0"),
        (tcp("in", "0f0000000a020301", 10), "write 1 1 0 0 0 0 0 0 1 0"),
        (tcp("in", "10000000020400010002", 2), "write H'0001' H'0002'"),
        (tcp("in", "03000000020", 2), ""),  # odd hex: not a frame to decode
        (tcp("in", "0300000002", 2), ""),  # a read request carries no values
        (tcp("out", "0601000001", 1), ""),  # a write's echo: the request said it
        (tcp("out", "8302", 2, exception=2), ""),
        (tcp("out", "0304", 2), ""),  # cut short: what is there, nothing invented
    ],
)
def test_the_values_of_a_frame(record: dict[str, object], shown: str) -> None:
    assert frame_values(record) == shown


def test_a_long_read_is_bounded_and_counted() -> None:
    words = "".join(f"{i:04x}" for i in range(100))
    line = frame_values(tcp("out", f"03c8{words}", 100))
    assert line.startswith("read H'0000' H'0001' ")
    assert len(line.split()) == 1 + VALUES_SHOWN + 3 and line.endswith("... 84 more")


def test_a_line_fault_and_serial_characters_have_no_values() -> None:
    fault = {"kind": "modbus", "dir": "in", "fault": "crc_errors", "hex": "0103"}
    assert frame_values(fault) == ""
    assert frame_values({"kind": "serial", "dir": "in", "text": "A", "hex": "41"}) == ""
    assert show_line(tcp("out", "03020009", 1)).endswith("from None: ok  read H'0009'")


def test_trace_show_prints_them(tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    records = [tcp("in", "10000000020400010002", 2, tes={"TES 32EST #1": "answers"})]
    records.append(tcp("out", "03040009ff00", 2, **{"from": "TES 32EST #1"}))
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "trace", "show", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    lines = done.stdout.splitlines()
    assert lines[0].endswith("TES 32EST #1 answers  write H'0001' H'0002'")
    assert lines[1].endswith("from TES 32EST #1: ok  read H'0009' H'FF00'")
