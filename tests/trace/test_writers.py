"""The server tap, the trace writer, the pcap writer and the console's trace command."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import dpkt
import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Link, WriteWord
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.plant import load_plant
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.modbus_server import serve_rtu
from fieldtwin.runtime.pcap import ISN_CLIENT, ISN_SERVER, PcapWriter
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.trace import TraceWriter, describe, read_records
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.memory import memory_pair
from tests.modbus.modbus_fakes import TableDevice

LINE = line_settings(38400, 8, "E", 1)
LIMIT = 2_000 * MS


@pytest.fixture
def runner() -> Iterator[Runner]:
    yield Runner(SimClock(), speed=None)


def _exchange(runner: Runner, bus: EventBus | None) -> tuple[bytes, int]:
    ours, master = memory_pair()
    device = TableDevice(1)
    server = serve_rtu(runner, ours, [device], Link.RS485, LINE)
    if bus is not None:
        server.tap(bus, "memory")
    master.send(with_crc(b"\x01" + encode_request(WriteWord(1, 5))))
    got = bytearray()

    def replied() -> bool:
        got.extend(master.receive())
        return len(got) >= 8

    assert runner.run_until(replied, LIMIT)
    pumps = list(server.pumps.values())
    stream_made = any(p._stream is not None for p in pumps)
    server.close()
    return bytes(got), runner.clock.now if not stream_made else -runner.clock.now


def test_an_unobserved_server_builds_nothing_and_an_observed_one_answers_the_same() -> None:
    quiet = _exchange(Runner(SimClock(), speed=None), EventBus())  # a bus nobody listens to
    bus = EventBus()
    sub = bus.subscribe()
    watched = _exchange(Runner(SimClock(), speed=None), bus)
    assert quiet[1] > 0  # no decoder was made while nobody listened
    assert watched == (quiet[0], -quiet[1])  # same reply at the same simulated instant
    events = sub.take()
    modbus = [e.data["dir"] for e in events if e.kind == "modbus"]
    assert modbus == ["in", "out"]  # and a write is also a "register" event
    assert {e.kind for e in events} <= {"modbus", "register"}


def _frames(bus: EventBus, clock: SimClock) -> None:
    data = {"endpoint": "tcp://127.0.0.1:0", "transport": "tcp", "listen": "tcp://127.0.0.1:5020"}
    request = bytes.fromhex("000100000006010300000002")
    reply = bytes.fromhex("00010000000701030400010000")
    bus.publish(
        clock.now,
        "modbus",
        "tcp://127.0.0.1:0 1",
        {
            **data,
            "conn": "127.0.0.1:40000",
            "dir": "in",
            "slave": 1,
            "function": 3,
            "function_name": "read_holding_registers",
            "address": 0,
            "count": 2,
            "tes": {"A": "answers"},
            "hex": request.hex(),
        },
    )
    bus.publish(
        clock.now + MS,
        "modbus",
        "tcp://127.0.0.1:0 1",
        {
            **data,
            "conn": "127.0.0.1:40000",
            "dir": "out",
            "slave": 1,
            "function": 3,
            "function_name": "read_holding_registers",
            "from": "A",
            "hex": reply.hex(),
        },
    )
    bus.publish(clock.now + 2 * MS, "modbus", "pty", {"transport": "rtu", "dir": "in", "hex": "00"})


def test_trace_writer_writes_one_line_per_event(tmp_path: Path) -> None:
    bus, clock = EventBus(), SimClock()
    path = tmp_path / "t.jsonl"
    writer = TraceWriter(bus, path, wall=lambda: 1000.5)
    _frames(bus, clock)
    bus.publish(5, "led", "5", {"led": "ERR"})  # not traffic: not traced
    writer.close()
    writer.close()  # idempotent
    records = read_records(path)
    assert [r["t"] for r in records] == [0.0, 0.001, 0.002]
    assert records[0]["wall"] == 1000.5 and records[0]["kind"] == "modbus"
    assert list(records[0])[:4] == ["t", "wall", "kind", "device"]
    assert describe(records[1]).endswith("out  slave 1  read_holding_registers  from A: ok")
    assert not bus.active  # closed: unsubscribed


def test_a_full_disk_is_reported_once_and_the_plant_keeps_publishing() -> None:
    bus, clock = EventBus(), SimClock()
    reports: list[str] = []
    writer = TraceWriter(bus, "/dev/full", report=reports.append)
    for _ in range(3000):  # more than the 64 KiB buffer
        _frames(bus, clock)
    writer.close()
    assert len(reports) == 1 and "tracing stopped, the plant keeps running" in reports[0]
    assert writer.failed is not None and not bus.active
    _frames(bus, clock)  # publishing still works (nobody listens)


def test_a_trace_file_that_cannot_be_opened_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"--trace .*: cannot write it"):
        TraceWriter(EventBus(), tmp_path / "no" / "such.jsonl")
    with pytest.raises(ConfigError, match=r"--pcap .*: cannot write it"):
        PcapWriter(EventBus(), tmp_path / "no" / "such.pcap")


def test_pcap_has_a_handshake_and_consistent_sequence_numbers(tmp_path: Path) -> None:
    bus, clock = EventBus(), SimClock()
    path = tmp_path / "t.pcap"
    writer = PcapWriter(bus, path, start_wall=1000.0)
    _frames(bus, clock)
    _frames(bus, clock)
    writer.close()
    with path.open("rb") as f:
        packets = [(ts, dpkt.ethernet.Ethernet(buf)) for ts, buf in dpkt.pcap.Reader(f)]
    segments = [eth.data.data for _, eth in packets]
    assert [s.flags & 0x3F for s in segments[:3]] == [0x02, 0x12, 0x10]  # SYN, SYN-ACK, ACK
    assert len(packets) == 3 + 4  # the RTU-on-pty frame is not in the pcap
    request, reply, request2, _ = segments[3:]
    assert (request.sport, request.dport) == (40000, 5020)
    assert (reply.sport, reply.dport) == (5020, 40000)
    assert request.seq == ISN_CLIENT + 1 and reply.seq == ISN_SERVER + 1
    assert request2.seq == request.seq + len(request.data) and request2.ack == reply.seq + 13
    assert packets[4][0] == pytest.approx(1000.001)


def test_console_trace_follows_the_scm_characters(tmp_path: Path) -> None:
    plant_file = tmp_path / "scm.toml"
    plant_file.write_text(
        '[plc]\nmodel = "TSX 87"\nscan_ms = 10\n[[module]]\ntype = "TSX SCM 2111"\nslot = 7\n'
        'channels = [{ channel = 0, endpoint = "memory", config = ["H\'0802\'", "H\'9600\'",'
        " 0, \"H'1001'\", \"H'1000'\", \"H'0D00'\", 0, 0] }]\n"
    )
    console = Console(load_plant(plant_file, speed=None))
    assert console.execute("trace") == ["trace off"]
    assert console.execute("trace on serial") == ["trace on (serial)"]
    console.execute("advance 1")
    console.execute("exchange H'0700' 1 text \"HI\"")
    out = console.execute("advance 1")
    assert out[0] == "t = 2.020 s"
    assert out[1:] == ["   1.011146 s  memory ch 0  out  2 chars 'HI'"]
    assert console.execute("trace show") == []
    assert console.execute("trace") == ["trace on (serial): 0 waiting, 0 dropped"]
    assert console.execute("trace off") == ["trace off"]
    with pytest.raises(ConfigError, match="trace on: unknown kind 'leds'"):
        console.execute("trace on leds")
    with pytest.raises(ConfigError, match=r"trace show: the trace is off"):
        console.execute("trace show")


def test_a_trace_record_is_json(tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    bus = EventBus()
    writer = TraceWriter(bus, path, wall=lambda: 0.0)
    bus.publish(
        1,
        "serial",
        "7",
        {"endpoint": "pty", "channel": 0, "dir": "in", "count": 1, "hex": "41", "text": "A"},
    )
    writer.close()
    assert json.loads(path.read_text()) == {
        "t": 1e-06,
        "wall": 0.0,
        "kind": "serial",
        "device": "7",
        "endpoint": "pty",
        "channel": 0,
        "dir": "in",
        "count": 1,
        "hex": "41",
        "text": "A",
    }
