"""§3.1.3 / §3.1.4 the two ports, RTU over TCP, answer delays: `fieldtwin run` at speed x1.

A second plant, run paced at x1 so that answer delays can be measured on the
wall clock (lower bounds only, with loose upper bounds):

* a TES 8ESA whose plant table puts a pty on its RS-232 port (``link = "rs232"``,
  no ``slave`` key): slave number, speed, parity and answer delay come from the
  RS-232 parameters of its EEPROM, written before the run the way TESIS would;
* a TES 32ST, 8EA, 4EA and 8SA-U behind one ``rtu+tcp://`` endpoint, reached
  with pymodbus's ``ModbusTcpClient(framer=FramerType.RTU)``.
"""

from __future__ import annotations

import re
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest
import serial
from pymodbus import FramerType
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from fieldtwin.tes import Tes
from tests.tes.blackbox.conftest import exception_code, start_plant, stop_plant, words, write
from tests.tes.blackbox.test_blackbox_line import crc16

ESA, ESA_RS485 = 7, 3  # TES 8ESA: its RS-232 and RS-485 slave numbers (EEPROM)
ST, EA, SLOW, SAU = 12, 13, 14, 15  # 32ST, 8EA (not ready), 4EA (slow), 8SA-U on rtu+tcp
ESA_DELAY_S, ESA_RS485_DELAY_S, SLOW_DELAY_S = 0.100, 2.000, 2.570  # §3.1.3, §7.2.7 max
LOOSE_S = 1.5  # the loose upper bound on top of a delay
IO_TIMEOUT_S = 4.0  # longer than the longest answer delay
NO_REPLY_S = 0.5  # wall time a reply on the RS-232 pty would need at most

PLANT = f"""[plant]
title = "tes ports"

[[tes]]
model = "TES 8ESA"
endpoint = "pty"
link = "rs232"
name = "esa"
store = "eeprom.db"
strict_line = false  # the masters below open the 8O1 pty 8N1 (pymodbus cannot set parity)

[[tes]]
model = "TES 32ST"
slave = {ST}
endpoint = "rtu+tcp://127.0.0.1:0"

[[tes]]
model = "TES 8EA"
slave = {EA}
endpoint = "rtu+tcp://127.0.0.1:0"
faults = {{ not_ready_ms = 50 }}

[[tes]]
model = "TES 4EA"
slave = {SLOW}
endpoint = "rtu+tcp://127.0.0.1:0"
name = "slow"
store = "eeprom.db"

[[tes]]
model = "TES 8SA-U"
slave = {SAU}
endpoint = "rtu+tcp://127.0.0.1:0"
inputs = {{ 0 = {{ kind = "pulse", period_s = 0.2, duty = 0.2 }} }}
"""

# §3.1.3 / §3.1.4 / §7.2.7 the EEPROMs a TESIS download leaves
EEPROMS: dict[tuple[str, str], dict[str, object]] = {
    ("TES 8ESA", "esa"): {
        "rs485.slave": ESA_RS485,
        "rs485.answer_delay_ms": round(ESA_RS485_DELAY_S * 1000),
        "rs232.slave": ESA,
        "rs232.baud": 19200,
        "rs232.parity": "O",
        "rs232.answer_delay_ms": round(ESA_DELAY_S * 1000),
    },
    ("TES 4EA", "slow"): {"rs485.answer_delay_ms": round(SLOW_DELAY_S * 1000)},
}

pytestmark = pytest.mark.timeout(30)  # every test bounded, setup included


@dataclass
class Ports:
    rs232_path: str
    rs232_line: str
    rtu_port: int
    rtu_line: str


@pytest.fixture(scope="module")
def ports(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Ports]:
    directory = tmp_path_factory.mktemp("tes_ports")
    for (model, name), values in EEPROMS.items():
        Tes(model, store=directory / "eeprom.db", name=name).write_eeprom(values)
    proc, lines = start_plant(directory, PLANT, 1)
    try:
        pty = next(m for x in lines if (m := re.match(r"listening: modbus-rtu pty (\S+) (.*)", x)))
        rtu = next(
            m for x in lines if (m := re.match(r"listening: modbus-rtu-over-tcp \S+:(\d+) (.*)", x))
        )
        yield Ports(pty.group(1), pty.group(2), int(rtu.group(1)), rtu.group(2))
    finally:
        stop_plant(proc)


@pytest.fixture(scope="module")
def rs232(ports: Ports) -> Iterator[ModbusSerialClient]:
    # Linux ptys refuse parity settings: the master opens the line 8N1 (docs/modbus.md)
    client = ModbusSerialClient(
        ports.rs232_path, baudrate=19200, parity="N", timeout=IO_TIMEOUT_S, retries=0
    )
    assert client.connect()
    yield client
    client.close()  # type: ignore[no-untyped-call]


@pytest.fixture(scope="module")
def rtu(ports: Ports) -> Iterator[ModbusTcpClient]:
    client = ModbusTcpClient(
        "127.0.0.1",
        port=ports.rtu_port,
        framer=FramerType.RTU,
        timeout=IO_TIMEOUT_S,
        retries=0,
    )
    assert client.connect()  # type: ignore[no-untyped-call]
    yield client
    client.close()  # type: ignore[no-untyped-call]


def _raw_rs232(ports: Ports, frame: bytes) -> bytes:
    """Send raw bytes on the RS-232 pty; whatever comes back within NO_REPLY_S."""
    with serial.Serial(ports.rs232_path, 19200, timeout=0) as port:
        port.write(frame)
        deadline, got = time.monotonic() + NO_REPLY_S, b""
        while time.monotonic() < deadline:
            got += port.read(64)
            time.sleep(0.01)
    return got


def _timed_read(client: ModbusSerialClient | ModbusTcpClient, slave: int) -> float:
    start = time.monotonic()
    words(client, slave, 0x000)
    return time.monotonic() - start


# --- RS-232 port (§3.1.4, §6.4.12.2) -----------------------------------------


def test_3_1_4_the_rs232_port_has_its_own_number_and_format(
    ports: Ports, rs232: ModbusSerialClient
) -> None:
    assert ports.rs232_line == f"slaves {ESA} (19200 8O1)"  # 8 data bits, 1 stop bit fixed
    assert not rs232.read_holding_registers(0x003, count=8, device_id=ESA).isError()
    frame = bytes((ESA_RS485, 0x03, 0x00, 0x00, 0x00, 0x01))
    assert _raw_rs232(ports, frame + crc16(frame)) == b""  # its RS-485 number: not on this port


def test_6_4_12_2_rs232_frames_are_counted_in_the_rs232_counters(
    ports: Ports, rs232: ModbusSerialClient
) -> None:
    before = words(rs232, ESA, 0x047, 14)  # RS-485 047h..04Dh, RS-232 04Eh..054h
    for _ in range(3):
        words(rs232, ESA, 0x003)
    assert exception_code(rs232.read_holding_registers(0x44F, count=1, device_id=ESA)) == 2
    frame = bytes((ESA, 0x03, 0x00, 0x00, 0x00, 0x01))
    good = crc16(frame)
    assert _raw_rs232(ports, frame + bytes((good[0] ^ 0x55, good[1]))) == b""  # CRC error
    other = bytes((ESA_RS485,)) + frame[1:]
    assert _raw_rs232(ports, other + crc16(other)) == b""  # a good frame, not for this port
    after = words(rs232, ESA, 0x047, 14)
    delta = [a - b for a, b in zip(after, before, strict=True)]
    assert delta[:7] == [0] * 7  # RS-485 counters untouched
    # exception, not ready, executed (first snapshot + 3), CRC, wrong chars, good, no silence
    assert delta[7:] == [1, 0, 1 + 3, 1, 0, 3 + 1 + 1 + 1, 0]


def test_amb_tes_10_rs232_requests_do_not_feed_the_rs485_watchdog(
    rs232: ModbusSerialClient,
) -> None:
    """§6.4.11.1 "two master requests on RS485": a master on RS-232 only sees the fallback."""
    write(rs232, ESA, 0x014 + 4, 5000)  # analog output 4 (the 8ESA's first, §6.4.6)
    write(rs232, ESA, 0x03E + 4, 1234)  # its fallback value
    write(rs232, ESA, 0x046, 0x0010)  # output 4 may fall back
    write(rs232, ESA, 0x03D, 0x0005)  # digital fallback: outputs 0 and 2 on, fixed
    write(rs232, ESA, 0x013, 0x000A)  # outputs 1 and 3 on
    write(rs232, ESA, 0x03C, 3)  # 0.3 s of silence on RS-485
    gaps, last, status = [], time.monotonic(), 0
    deadline = last + 5.0
    while not status & 0x02:
        assert time.monotonic() < deadline, "no fallback"
        status = words(rs232, ESA, 0x000)[0]
        gaps.append(time.monotonic() - last)
        last = time.monotonic()
    assert max(gaps) < 0.3  # requests kept coming on RS-232 faster than the watching time
    write(rs232, ESA, 0x03C, 0)
    assert words(rs232, ESA, 0x018) == [1234]  # §6.4.11.3
    assert words(rs232, ESA, 0x00B + 4)[0] & 0x02  # §6.4.4 bit 1
    assert words(rs232, ESA, 0x013) == [0x0005]  # §6.4.11.2
    assert words(rs232, ESA, 0x01C)[0] >> 8 == 0x5  # direct outputs


# --- answer delay (§3.1.3, §3.1.4, §7.2.7) ---------------------------------------


def test_3_1_4_rs232_answer_delay_is_the_rs232_parameter(rs232: ModbusSerialClient) -> None:
    for _ in range(3):
        elapsed = _timed_read(rs232, ESA)
        # no earlier than the RS-232 delay; far from the RS-485 one (2 s)
        assert ESA_DELAY_S <= elapsed <= ESA_RS485_DELAY_S - 0.5


def test_7_2_7_answer_delay_2570_ms_on_rtu_over_tcp(rtu: ModbusTcpClient) -> None:
    elapsed = _timed_read(rtu, SLOW)
    assert SLOW_DELAY_S <= elapsed <= SLOW_DELAY_S + LOOSE_S
    # the others behind the same endpoint keep their own delay (0): not held by the 4EA
    assert _timed_read(rtu, ST) < SLOW_DELAY_S


# --- RTU over TCP --------------------------------------------------------------


def test_rtu_over_tcp_with_the_pymodbus_rtu_framer(ports: Ports, rtu: ModbusTcpClient) -> None:
    assert ports.rtu_line == f"slaves {ST},{EA},{SLOW},{SAU} (38400 8E1)"
    counters = {ST: 0x017, SAU: 0x047}  # RS-485 then RS-232 counters (§6.3.4, §6.4.12)
    before = {s: words(rtu, s, a, 14) for s, a in counters.items()}
    assert len(words(rtu, ST, 0x000, 0x025)) == 0x025  # the whole 32ST map
    assert exception_code(rtu.read_holding_registers(0x025, count=1, device_id=ST)) == 2
    assert not rtu.write_coil(0x05 * 16 + 3, True, device_id=ST).isError()  # §7.1.2 bit 53h
    coils = rtu.read_coils(0x01 * 16, count=8, device_id=ST)
    assert coils.bits[:8] == [False, False, False, True, False, False, False, False]
    quick = rtu.read_exception_status(device_id=ST)
    assert quick.status == words(rtu, ST, 0x000)[0] & 0xFF  # §7.2.6
    write(rtu, ST, 0x005, 0x0000)
    with socket.create_connection(("127.0.0.1", ports.rtu_port), timeout=2.0) as raw:
        frame = bytes((ST, 0x03, 0x00, 0x00, 0x00, 0x01))
        good = crc16(frame)
        raw.sendall(frame + bytes((good[0], good[1] ^ 0x0F)))
        time.sleep(0.3)  # the stream flush (50 ms at x1) counts it
    after = {s: words(rtu, s, a, 14) for s, a in counters.items()}
    st = [a - b for a, b in zip(after[ST], before[ST], strict=True)]
    # exception, not ready, executed (snapshot + 6), CRC, wrong chars, good (8-SAU + 1), silence
    assert st[:7] == [1, 0, 7, 1, 0, 9, 0]  # RTU over TCP counts as RS-485
    assert st[7:] == [0] * 7
    sau = [a - b for a, b in zip(after[SAU], before[SAU], strict=True)]
    assert sau[3] == 1 and sau[7:] == [0] * 7  # every TES on the line counts the CRC error


# --- TES 32ST: 32-bit fallback masks and blinking (§6.3) -------------------------


def test_6_3_3_32st_fallback_with_32_bit_or_and_masks(rtu: ModbusTcpClient) -> None:
    write(rtu, ST, 0x003, 0x0000, 0x0000, 0xFFFF, 0xFFFF)  # all 32 outputs fixed at 1
    # OR word 0 (blink select) [15..00] [31..16], OR word 1 (states), AND word 0, AND word 1
    write(rtu, ST, 0x00E, 0x0000, 0x0001, 0x0000, 0x8000, 0x0000, 0x0000, 0x00FF, 0x0001)
    write(rtu, ST, 0x000, 0x0000)
    write(rtu, ST, 0x016, 3)  # §6.3.3 0.3 s between two master requests (Tb = 100 ms)
    for _ in range(6):  # requests every ~0.1 s keep the outputs
        time.sleep(0.1)
        assert words(rtu, ST, 0x000)[0] & 0x02 == 0
    time.sleep(0.8)  # silence to this TES
    assert words(rtu, ST, 0x000)[0] & 0x02  # §6.3.1 bit 1
    # AMB-TES-11 (command AND and-mask) OR or-mask on 32 bits: output 16 blinks at
    # frequency 1 (its state bit kept), outputs 0..7 and 31 on, the others off
    assert words(rtu, ST, 0x003, 4) == [0x0000, 0x0001, 0x00FF, 0x8001]
    seen = set()
    for _ in range(30):
        low, high = words(rtu, ST, 0x001, 2)
        assert low == 0x00FF and high & 0xFFFE == 0x8000
        seen.add(high & 1)
        time.sleep(0.007)
    assert seen == {0, 1}  # §3.1.2 frequency 1 = 10 Hz
    write(rtu, ST, 0x016, 0)
    write(rtu, ST, 0x003, 0x0000, 0x0000, 0x1234, 0x0000)  # recovery: the master commands
    assert words(rtu, ST, 0x001, 2) == [0x1234, 0x0000]


def _agreement(pairs: list[tuple[int, int]]) -> float:
    return sum(a == b for a, b in pairs) / len(pairs)


def test_6_3_2_32st_blinking_on_the_upper_word(rtu: ModbusTcpClient) -> None:
    """Output 17 at frequency 0 = the 8SA-U's input pulse (40 ms on of 200 ms), output 31
    at frequency 1 (30 / 30 ms), output 16 fixed at 1; same clock, same power-on.

    Blinking at the wrong frequency would agree with the pulse about half of the time.
    """
    write(rtu, ST, 0x007, 8, 32, 6, 6)  # §6.3.2 durations, Tb = 5 ms
    write(rtu, ST, 0x003, 0x0000, 0x8002, 0x0000, 0x8001)
    pairs, on31 = [], 0
    samples = 60
    for _ in range(samples):
        high = words(rtu, ST, 0x002)[0]
        pulse = words(rtu, SAU, 0x001)[0] & 1  # filtered input 0 (5 ms filter)
        assert high & 0x7FFD == 0x0001  # 16 on, 18..30 off
        pairs.append(((high >> 1) & 1, pulse))
        on31 += high >> 15
        time.sleep(0.011)
    assert {a for a, _ in pairs} == {0, 1}
    assert _agreement(pairs) >= 0.8  # the two reads are a few ms apart
    assert 0.25 * samples <= on31 <= 0.75 * samples
    write(rtu, ST, 0x003, 0x0000, 0x0000, 0x0000, 0x0000)


# --- analog models: digital outputs (§6.4.5) and "not ready" (§6.4.13) -----------


def test_6_4_5_blinking_digital_outputs_of_an_8sa_u(rtu: ModbusTcpClient) -> None:
    write(rtu, SAU, 0x01F, 8, 32, 6, 6)  # §6.4.7 blinking durations, Tb = 5 ms
    # bits 11-08: outputs 0 and 1 blink; bits 03-00: output 0 frequency 0, 1 frequency 1,
    # output 2 fixed 0, output 3 fixed 1
    write(rtu, SAU, 0x013, 0x030A)
    pairs, on1 = [], 0
    samples = 60
    for _ in range(samples):
        reply = words(rtu, SAU, 0x001, 0x01C)  # one request: one simulated instant
        pulse, outputs = reply[0] & 1, reply[0x01C - 0x001] >> 8
        assert outputs & 0xC == 0x8
        pairs.append((outputs & 1, pulse))
        on1 += (outputs >> 1) & 1
        time.sleep(0.011)
    assert {a for a, _ in pairs} == {0, 1}
    assert _agreement(pairs) >= 0.8  # apart from the 5 ms input filter after each edge
    assert 0.25 * samples <= on1 <= 0.75 * samples
    write(rtu, SAU, 0x013, 0x0000)


def test_amb_tes_28_not_ready_from_056h_on_the_analog_map(rtu: ModbusTcpClient) -> None:
    before = words(rtu, EA, 0x047, 2)
    codes: dict[int, set[int]] = {0x057: set(), 0x41F: set()}
    for _ in range(100):
        for address, seen in codes.items():
            reply = rtu.read_holding_registers(address, count=2, device_id=EA)
            seen.add(exception_code(reply) if reply.isError() else 0)
        if all(seen == {0, 4} for seen in codes.values()):
            break
        time.sleep(0.007)
    assert codes == {0x057: {0, 4}, 0x41F: {0, 4}}  # history and 32-bit counters
    for _ in range(20):  # up to 055h: never refused
        assert not rtu.read_holding_registers(0x047, count=15, device_id=EA).isError()
        assert not rtu.write_register(0x055, 1, device_id=EA).isError()
        time.sleep(0.005)
    exceptions, not_ready = (a - b for a, b in zip(words(rtu, EA, 0x047, 2), before, strict=True))
    assert exceptions == 0 and not_ready >= 2  # §6.4.12.1 counted as "slave not ready"
