"""Black box: under `fieldtwin run` the observers work in a process of their own.

The events of two `/events` subscribers, the trace and the pcap are made there
(fieldtwin.runtime.obsproc); they stay complete and in order against the frames a
master sent, a subscriber with a small queue loses only its own events, and the
process never outlives `fieldtwin run` (SIGTERM, or killed outright).
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import dpkt
import pytest

pytest.importorskip("websockets")
from websockets.sync.client import connect

ROOT = Path(__file__).resolve().parents[2]
PLANT = '[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:0"\n'
REQUESTS = 150
WAIT_S = 30.0


def _start(tmp: Path, *extra: str) -> tuple[subprocess.Popen[str], int, str]:
    plant = tmp / "plant.toml"
    plant.write_text(PLANT)
    argv = [sys.executable, "-m", "fieldtwin", "run", str(plant), "--no-live", *extra]
    proc = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
    )
    assert proc.stdout is not None
    port, control = 0, ""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline and not (port and (control or "--no-control" in extra)):
        line = proc.stdout.readline()
        if not line:
            break
        if m := re.search(r"modbus-tcp tcp://127\.0\.0\.1:(\d+)", line):
            port = int(m.group(1))
        if m := re.match(r"control: (http://\S+)", line):
            control = m.group(1)
    assert port, "the endpoint was not announced"
    return proc, port, control


def _children(pid: int) -> list[int]:
    out: list[int] = []
    for task in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{task}/children") as f:
            out.extend(int(child) for child in f.read().split())
    return out


def _observers(pid: int) -> int:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        for child in _children(pid):
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes()
            if b"fieldtwin.runtime.obsproc" in cmdline:
                return child
        time.sleep(0.05)
    raise AssertionError("no observers' process under fieldtwin run")


def _gone(pid: int) -> bool:
    """``pid`` ended (or is a zombie waiting for its new parent to reap it)."""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.05)
    return False


def _master(port: int, count: int) -> None:
    """``count`` FC03 requests, transactions 1..count, one after the other."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        for transaction in range(1, count + 1):
            sock.sendall(struct.pack(">HHHBBHH", transaction, 0, 6, 1, 3, 37, 10))
            reply = b""
            while len(reply) < 9 or len(reply) < 6 + struct.unpack(">H", reply[4:6])[0]:
                chunk = sock.recv(512)
                assert chunk, "the server closed the connection"
                reply += chunk
            assert struct.unpack(">H", reply[:2])[0] == transaction


def _read(ws: Any, until: int) -> tuple[list[dict[str, Any]], int]:
    """The modbus events and the count said dropped, until ``until`` are accounted for."""
    events: list[dict[str, Any]] = []
    dropped = 0
    deadline = time.monotonic() + WAIT_S
    while len(events) + dropped < until and time.monotonic() < deadline:
        try:
            message = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
        except TimeoutError:
            break
        for item in json.loads(message):
            if item["kind"] == "dropped":
                dropped += item["count"]
            elif item["kind"] == "modbus":
                events.append(item)
    return events, dropped


def test_events_trace_and_pcap_are_complete_and_in_order(tmp_path: Path) -> None:
    trace, pcap = tmp_path / "t.jsonl", tmp_path / "t.pcap"
    proc, port, control = _start(
        tmp_path, "--control-port", "0", "--trace", str(trace), "--pcap", str(pcap)
    )
    try:
        child = _observers(proc.pid)
        url = control.replace("http://", "ws://") + "/events?batch=1&kind=modbus"
        with connect(url) as reader, connect(url + "&queue=1") as small:
            time.sleep(0.3)  # both subscriptions reach the observers' process
            _master(port, REQUESTS)
            events, dropped = _read(reader, 2 * REQUESTS)
            small_events, small_dropped = _read(small, 2 * REQUESTS)
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=WAIT_S)
    assert proc.returncode == 0, err
    assert _gone(child), "the observers' process outlived fieldtwin run"
    expected = [(d, t) for t in range(1, REQUESTS + 1) for d in ("in", "out")]
    assert dropped == 0
    assert [(e["dir"], e["transaction"]) for e in events] == expected
    # the small queue lost its own oldest events, counted; the other lost none
    assert len(small_events) + small_dropped == 2 * REQUESTS
    got = [(e["dir"], e["transaction"]) for e in small_events]
    assert got == [pair for pair in expected if pair in set(got)]  # what it kept, in order
    # the files, written in the observers' process, are complete once the run ended
    lines = [json.loads(line) for line in trace.read_text().splitlines()]
    modbus = [(r["dir"], r["transaction"]) for r in lines if r["kind"] == "modbus"]
    assert modbus == expected
    with pcap.open("rb") as f:
        payloads = [
            bytes(dpkt.ethernet.Ethernet(buf).data.data.data) for _, buf in dpkt.pcap.Reader(f)
        ]
    data = [p for p in payloads if p]
    assert len(data) == 2 * REQUESTS
    assert [struct.unpack(">H", p[:2])[0] for p in data[:4]] == [1, 1, 2, 2]


def test_the_observers_process_ends_with_a_killed_run(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    proc, port, _ = _start(tmp_path, "--no-control", "--trace", str(trace))
    try:
        child = _observers(proc.pid)
        _master(port, 5)
    finally:
        proc.kill()  # no close at all: the end of its stdin ends the observers' process
        proc.communicate(timeout=WAIT_S)
    assert _gone(child), "the observers' process outlived a killed fieldtwin run"
