"""Issue 23: every byte accounted for - bytes the TES's line rejected are in
``fieldtwin trace show`` with their reason (a real `fieldtwin run --trace`, pyserial)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import serial

from fieldtwin.modbus.crc import with_crc
from fieldtwin.testing.process import RunningPlant

PLANT = Path(__file__).parent / "plants" / "tes_pty.toml"
READ = with_crc(bytes([1, 0x03, 0x00, 0x05, 0x00, 0x01]))
MASK_WRITE = with_crc(bytes([1, 0x16, 0x00, 0x0D, 0xFF, 0x00, 0x00, 0x01]))  # FC 22
WAIT_S = 0.5


def send(path: str, data: bytes, baud: int = 38400, want: int = 16) -> bytes:
    """What comes back: ``want`` bytes, or what came within WAIT_S (3 s when an answer
    of ``want`` bytes is expected: a loaded machine)."""
    with serial.Serial(path, baud, parity="E", timeout=WAIT_S if want == 16 else 3.0) as port:
        port.write(data)
        return bytes(port.read(want))


def test_rejected_bytes_and_function_codes_in_trace_show(tmp_path: Path) -> None:
    trace = tmp_path / "line.jsonl"
    running = RunningPlant(PLANT, speed=None, args=["--trace", str(trace)])
    running.start()
    try:
        path = running.modbus(1).url
        assert send(path, READ[:-1] + bytes([READ[-1] ^ 0xFF])) == b""  # a bad CRC
        assert send(path, READ, baud=9600) == b""  # a master at the wrong speed
        assert len(send(path, MASK_WRITE, want=5)) == 5  # FC 22: exception 01 (TES 7.1.1)
    finally:
        running.stop()
    shown = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "trace", "show", str(trace)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    bad = READ[:-1] + bytes([READ[-1] ^ 0xFF])
    spaced = " ".join(f"{b:02x}" for b in bad)
    assert f"line fault crc_errors x1 (bad_crc): {spaced}" in shown, shown
    spaced = " ".join(f"{b:02x}" for b in READ)
    assert (
        f"line fault wrong_characters x8 (line_settings): {spaced}"
        "  [line settings differ: master 9600 8E1, TES 38400 8E1]"
    ) in shown, shown
    assert "mask_write_register  [FC 22 = 0x16]" in shown, shown
    assert "function_16" not in shown
