"""§7 three TES sharing one RS-485 line (pty line B, slaves 31, 32, 33).

Each answers only its own number and counts the others' frames only as good
frames (§6.2.3.2 reading in docs/manual-notes.md); all act on a broadcast;
fc 07; exception codes 1 and 2; frames with a bad CRC and short frames get
no reply and are counted by every TES on the line.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
import serial
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from tests.tes.blackbox.conftest import (
    LINE_B_SLAVES,
    SPEED,
    Running,
    exception_code,
    pair,
    sim_ticks,
    wait_sim,
    words,
    write,
)

EXC, NOT_READY, EXECUTED, CRC, WRONG, GOOD, NO_SILENCE = range(7)  # 017h..01Dh
NO_REPLY_S = 0.3  # wall time a reply would need at most

pytestmark = pytest.mark.timeout(30)  # every test bounded, setup included


def crc16(data: bytes) -> bytes:
    """Modbus CRC-16 (A001h reflected, init FFFFh), low byte first (AMB-TES-03)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return bytes((crc & 0xFF, crc >> 8))


@pytest.fixture
def raw(running: Running, line_b: ModbusSerialClient) -> Iterator[serial.Serial]:
    port = serial.Serial(running.line_b, 38400, bytesize=8, parity="N", stopbits=1, timeout=0)
    try:
        yield port
    finally:
        port.close()


def _answer(port: serial.Serial, frame: bytes) -> bytes:
    """Send raw bytes; whatever comes back within NO_REPLY_S."""
    port.reset_input_buffer()
    port.write(frame)
    deadline, got = time.monotonic() + NO_REPLY_S, b""
    while time.monotonic() < deadline:
        got += port.read(64)
        time.sleep(0.01)
    return got


def _counters(line_b: ModbusSerialClient) -> dict[int, list[int]]:
    return {s: words(line_b, s, 0x017, 7) for s in LINE_B_SLAVES}


def _delta(before: dict[int, list[int]], after: dict[int, list[int]]) -> dict[int, list[int]]:
    return {s: [a - b for a, b in zip(after[s], before[s], strict=True)] for s in before}


def test_6_2_3_2_each_answers_its_own_number_and_counts_the_others(
    line_b: ModbusSerialClient,
) -> None:
    before = _counters(line_b)
    for _ in range(4):
        words(line_b, 31, 0x003)
    reply = line_b.read_holding_registers(0x1A5, count=1, device_id=31)  # past the 16EST map
    assert exception_code(reply) == 2
    after = _counters(line_b)
    delta = _delta(before, after)
    # between a slave's two snapshots: 3 snapshot reads + 5 frames to slave 31
    assert delta[31] == [1, 0, 1 + 4, 0, 0, 3 + 5, 0]
    assert delta[32] == [0, 0, 1, 0, 0, 3 + 5, 0]
    assert delta[33] == [0, 0, 1, 0, 0, 3 + 5, 0]


def test_7_2_6_broadcast_is_executed_by_all_without_reply(
    line_b: ModbusSerialClient, tcp: ModbusTcpClient
) -> None:
    wait_sim(tcp, 10.0)
    before = {s: pair(*words(line_b, s, 0x025, 2)) for s in LINE_B_SLAVES}
    assert all(before.values())
    start = sim_ticks(tcp)
    # "synchronisation of commands, counters reset": outputs 0 and 2 on, counters 0
    reply = line_b.write_registers(0x00C, [0, 0x0005], device_id=0, no_response_expected=True)
    assert reply is None or not reply.isError()
    time.sleep(0.05)
    line_b.write_registers(0x025, [0, 0], device_id=0, no_response_expected=True)
    time.sleep(0.05)
    for slave, period in zip(LINE_B_SLAVES, (2, 3, 5), strict=True):
        assert words(line_b, slave, 0x007) == [0x0005]
        rises = pair(*words(line_b, slave, 0x025, 2))
        elapsed = sim_ticks(tcp) - start + 1
        assert rises <= elapsed // period + 1 < before[slave]


def test_7_2_6_fc07_is_the_low_byte_of_the_status_word(line_b: ModbusSerialClient) -> None:
    for slave in LINE_B_SLAVES:
        write(line_b, slave, 0x000, 0x0000)
        quick = line_b.read_exception_status(device_id=slave)
        assert not quick.isError()
        status = words(line_b, slave, 0x000)[0]
        assert quick.status == status & 0xFF
        assert quick.status & 0x08  # the pulse input's changes wait in the memorized word


def test_7_2_error_code_1_unknown_function(line_b: ModbusSerialClient, raw: serial.Serial) -> None:
    reply = line_b.diag_read_bus_message_count(device_id=32)  # fc 08: not a TES function
    assert exception_code(reply) == 1
    frame = bytes((33, 0x41, 0x00, 0x00))
    assert _answer(raw, frame + crc16(frame)) == bytes((33, 0xC1, 0x01)) + crc16(b"\x21\xc1\x01")


def test_7_1_3_bad_crc_is_unanswered_and_counted_by_every_tes(
    line_b: ModbusSerialClient, raw: serial.Serial
) -> None:
    before = _counters(line_b)
    frame = bytes((31, 0x03, 0x00, 0x03, 0x00, 0x01))
    good_crc = crc16(frame)
    assert _answer(raw, frame + bytes((good_crc[0] ^ 0xFF, good_crc[1]))) == b""
    assert len(_answer(raw, frame + good_crc)) == 7  # the same frame, well formed, is answered
    delta = _delta(before, _counters(line_b))
    for slave in LINE_B_SLAVES:
        assert delta[slave][CRC] == 1
        assert delta[slave][GOOD] == 3 + 1  # snapshot reads and the good frame only
    assert delta[31][EXECUTED] == 1 + 1


def test_7_2_short_frames_are_unanswered_and_counted_as_wrong_characters(
    line_b: ModbusSerialClient, raw: serial.Serial
) -> None:
    before = _counters(line_b)
    assert _answer(raw, bytes((32, 0x03, 0x00))) == b""  # 3 bytes: shorter than any frame
    time.sleep(5 / SPEED)
    delta = _delta(before, _counters(line_b))
    for slave in LINE_B_SLAVES:
        assert delta[slave][WRONG] == 3
        assert delta[slave][GOOD] == 3
        assert delta[slave][EXC] == delta[slave][CRC] == 0
