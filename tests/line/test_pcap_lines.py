"""Issue 23: one ``--pcap`` file that tshark decodes both ways - a TCP session (with the
FIN of a dropped connection and of a master that hung up) and an RTU pty session as a
synthetic stream (``-d tcp.port==65020,mbrtu``, docs/trace.md)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import serial
from pymodbus.client import ModbusTcpClient

from fieldtwin.modbus.crc import with_crc
from fieldtwin.runtime.pcap import RTU_PORT
from fieldtwin.testing.process import RunningPlant
from tests.systools import require

PLANT = Path(__file__).parent / "plants" / "tcp_and_pty.toml"
READ_2 = with_crc(bytes([2, 0x03, 0x00, 0x05, 0x00, 0x01]))


def tshark_rows(tshark: str, pcap: Path, tcp: int, *fields: str, where: str) -> list[list[str]]:
    argv = [tshark, "-r", str(pcap), "-d", f"tcp.port=={tcp},mbtcp"]
    argv += ["-d", f"tcp.port=={RTU_PORT},mbrtu", "-Y", where, "-T", "fields"]
    for name in fields:
        argv += ["-e", name]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=True)
    return [line.split("\t") for line in done.stdout.splitlines()]


def exchange(path: str) -> None:
    with serial.Serial(path, 38400, parity="E", timeout=3.0) as port:
        port.write(READ_2)
        assert len(port.read(7)) == 7


def test_tshark_decodes_rtu_and_tcp_and_sees_the_closes(tmp_path: Path) -> None:
    tshark = require("tshark")
    pcap = tmp_path / "both.pcap"
    running = RunningPlant(PLANT, speed=None, args=["--pcap", str(pcap)])
    running.start()
    try:
        tcp = running.modbus(1)
        exchange(running.modbus(2).url)
        dropped = ModbusTcpClient(tcp.host, port=tcp.port, timeout=2, retries=0)
        assert dropped.connect()
        assert not dropped.read_holding_registers(5, count=1, device_id=1).isError()
        running.api.set_fault("tes1", "drop_connections")  # the twin closes: its FIN
        hung_up = ModbusTcpClient(tcp.host, port=tcp.port, timeout=2, retries=0)
        assert hung_up.connect()
        assert not hung_up.read_holding_registers(5, count=1, device_id=1).isError()
        hung_up.close()  # type: ignore[no-untyped-call]  # the master closes: its FIN
        dropped.close()  # type: ignore[no-untyped-call]
        exchange(running.modbus(2).url)  # a round trip through the twin after the closes
    finally:
        running.stop()
    rtu = tshark_rows(tshark, pcap, tcp.port, "mbrtu.unit_id", "modbus.func_code", where="mbrtu")
    assert rtu == [["2", "3"]] * 4  # two queries and their replies on the pty
    tcp_frames = tshark_rows(tshark, pcap, tcp.port, "mbtcp.unit_id", where="mbtcp")
    assert tcp_frames == [["1"]] * 4
    closes = tshark_rows(
        tshark, pcap, tcp.port, "tcp.stream", "tcp.srcport", where="tcp.flags.fin == 1"
    )
    first_fin = {}
    for stream, source in closes:
        first_fin.setdefault(stream, int(source))
    # one connection closed by the twin (its port sends the first FIN), one by the master
    assert sorted(source == tcp.port for source in first_fin.values()) == [False, True]
