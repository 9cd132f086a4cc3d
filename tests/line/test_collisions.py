"""Issue 23: half-duplex collisions on the simulated clock.  On a two-wire RS-485 line
a master that sends the next request before the reply went out garbles both: no
reply, one CRC error for every slave (TES 6.2.3.2 01Ah), the collision in the event
stream with the bytes; a point-to-point RS-232 line answers both requests."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from fieldtwin.clock import MS, SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Counter, Link
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.modbus_server import serve_rtu
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.trace import TraceWriter
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.memory import memory_pair
from tests.modbus.modbus_fakes import TableDevice

SETTINGS = line_settings(38400, 8, "E", 1)
READ_1 = with_crc(bytes([1, 0x03, 0x00, 0x00, 0x00, 0x01]))
READ_2 = with_crc(bytes([2, 0x03, 0x00, 0x00, 0x00, 0x01]))


def run(
    link: Link, trace: Path | None = None
) -> tuple[bytes, TableDevice, TableDevice, list[dict[str, object]]]:
    runner = Runner(SimClock(), speed=None)
    ours, master = memory_pair()
    one, two = TableDevice(1, delay_us=20 * MS), TableDevice(2)
    server = serve_rtu(runner, ours, [one, two], link, SETTINGS)
    bus = EventBus()
    server.tap(bus, "pty")
    seen = bus.subscribe(("modbus",))
    writer = TraceWriter(bus, trace) if trace is not None else None
    try:
        master.send(READ_1)
        runner.advance(5 * MS)  # slave 1 is in its 20 ms answer delay
        master.send(READ_2)  # Node-RED's parallel polling: the next unit id at once
        runner.advance(100 * MS)
        got = master.receive()
    finally:
        server.close()
        if writer is not None:
            writer.close()
    return got, one, two, [dict(e.data) for e in seen.take()]


def test_a_request_over_a_reply_on_a_two_wire_line_collides() -> None:
    got, one, two, events = run(Link.RS485)
    assert got == b""  # the reply is lost, the second request never made a frame
    for device in (one, two):
        assert device.counted(Counter.CRC_ERRORS) == 1
    collided = [e for e in events if e.get("reason") == "collision"]
    assert len(collided) == 1 and collided[0]["hex"] == READ_2.hex()
    assert (collided[0]["fault"], collided[0]["fault_count"]) == ("crc_errors", 1)


def test_a_point_to_point_rs232_line_answers_both() -> None:
    got, one, two, events = run(Link.RS232)
    assert got.count(bytes([1, 0x03, 0x02])) == 1 and got.count(bytes([2, 0x03, 0x02])) == 1
    assert one.counted(Counter.CRC_ERRORS, Link.RS232) == 0
    assert not [e for e in events if e.get("reason") == "collision"]


def test_the_collision_is_in_trace_show(tmp_path: Path) -> None:
    trace = tmp_path / "collision.jsonl"
    run(Link.RS485, trace)
    shown = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "trace", "show", str(trace)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    spaced = " ".join(f"{b:02x}" for b in READ_2)
    assert f"line fault crc_errors x1 (collision): {spaced}" in shown, shown
    assert "the master sent while a reply was due; the reply is lost" in shown, shown
