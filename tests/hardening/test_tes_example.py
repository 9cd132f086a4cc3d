"""examples/tes.toml: an RTU multi-drop line on a pty and a TCP unit, polled as users would."""

from __future__ import annotations

import re
from pathlib import Path

from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from tests.tes.blackbox.conftest import start_plant, stop_plant

ROOT = Path(__file__).resolve().parents[2]


def test_the_tes_example_answers_on_its_line_and_its_tcp_unit(tmp_path: Path) -> None:
    text = (ROOT / "examples" / "tes.toml").read_text().replace(":5022", ":0")
    proc, lines = start_plant(tmp_path, text, speed=1.0)
    try:
        joined = "\n".join(lines)
        pty = re.search(r"listening: modbus-rtu pty (\S+) slaves 1,2,5", joined)
        tcp = re.search(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves 7", joined)
        assert pty and tcp, joined
        # Linux ptys refuse parity settings: the master opens the line 8N1 (docs/modbus.md)
        line = ModbusSerialClient(pty.group(1), baudrate=38400, timeout=2, retries=1)
        assert line.connect()
        try:
            for slave in (1, 2, 5):
                reply = line.read_holding_registers(0, count=1, device_id=slave)
                assert not reply.isError(), (slave, reply)
            inputs = line.read_holding_registers(3, count=1, device_id=1)
            assert inputs.registers[0] & 0b1000  # input 3 = true in the plant file
        finally:
            line.close()
        unit = ModbusTcpClient("127.0.0.1", port=int(tcp.group(1)), timeout=2)
        assert unit.connect()
        try:
            reply = unit.read_holding_registers(0, count=1, device_id=7)
            assert not reply.isError(), reply
        finally:
            unit.close()
    finally:
        stop_plant(proc)
