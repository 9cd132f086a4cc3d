"""Issue 23: a master whose pty settings differ from the TES's line gets what a UART
at the TES's settings makes of its bytes - no answer, the TES's wrong-character
counter (TES 6.2.3.2 01Bh) grows - and the right settings get answers; the plant key
``strict_line = false`` reads every master as if it were set right.  A real
``fieldtwin run`` and pyserial, as a user would."""

from __future__ import annotations

import pytest
import serial

from fieldtwin.modbus.crc import with_crc
from fieldtwin.testing.process import RunningPlant

READ_INPUTS = with_crc(bytes([1, 0x03, 0x00, 0x05, 0x00, 0x01]))  # word 005h: input 2 on
READ_WRONG_CHARACTERS = with_crc(bytes([1, 0x03, 0x00, 0x1B, 0x00, 0x01]))  # 01Bh
ANSWER = with_crc(bytes([1, 0x03, 0x02, 0x00, 0x04]))
WAIT_S = 0.5  # far beyond a 38400 Bd exchange (a few ms): how long "no answer" is waited for
ANSWER_S = 3.0  # the bound on an answer (a loaded machine, a plant just started)


def exchange(
    path: str, request: bytes, baud: int = 38400, parity: str = "E", wait: float = ANSWER_S
) -> bytes:
    with serial.Serial(path, baud, parity=parity, timeout=wait) as port:
        port.write(request)
        return bytes(port.read(7))


def wrong_characters(path: str) -> int:
    reply = exchange(path, READ_WRONG_CHARACTERS)
    assert len(reply) == 7, reply.hex()
    return int.from_bytes(reply[3:5], "big")


@pytest.mark.plant("plants/tes_pty.toml")
@pytest.mark.parametrize(("baud", "parity"), [(9600, "E"), (115200, "E"), (38400, "O")])
def test_a_master_at_other_settings_gets_no_answer(
    running_plant: RunningPlant, baud: int, parity: str
) -> None:
    path = running_plant.modbus(1).url
    assert exchange(path, READ_INPUTS) == ANSWER  # the right settings: an answer
    before = wrong_characters(path)
    assert exchange(path, READ_INPUTS, baud, parity, WAIT_S) == b""  # the TES read garbage
    assert wrong_characters(path) == before + len(READ_INPUTS)
    assert exchange(path, READ_INPUTS) == ANSWER  # set right again: answers again
    said = running_plant.output()
    shown = {"E": "8E1", "O": "8O1"}[parity]
    assert f"line settings differ: master {baud} {shown}, TES 38400 8E1" in said


@pytest.mark.plant("plants/tes_pty_lax.toml")
def test_strict_line_false_reads_every_master(running_plant: RunningPlant) -> None:
    path = running_plant.modbus(1).url
    before = wrong_characters(path)
    assert exchange(path, READ_INPUTS, 9600, "N") == ANSWER
    assert exchange(path, READ_INPUTS, 115200, "O") == ANSWER
    assert wrong_characters(path) == before
