"""Black box: every examples/ plant, run with `--record` and stimulated on its endpoints
(a Modbus master on TCP and on the RTU pty, characters typed into the SCM ptys), replays
identically."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from fieldtwin.modbus.crc import with_crc
from tests.record.runs import ROOT, Run, fieldtwin, free_port_plant, start

EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))
STIMULUS_S = 1.5


def _stimulate(run: Run) -> None:
    from pymodbus.client import ModbusTcpClient

    end = time.monotonic() + STIMULUS_S
    fds = [os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK) for path in run.rtu_ptys]
    scm = [os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK) for path in run.scm_ptys]
    clients = [ModbusTcpClient("127.0.0.1", port=p, timeout=1, retries=0) for p in run.tcp]
    try:
        for client in clients:
            assert client.connect()  # type: ignore[no-untyped-call]
        count = 0
        while time.monotonic() < end:
            for client in clients:
                client.read_input_registers(0, count=2, device_id=7)
            for fd in fds:  # read 2 holding registers of slave 1, then slave 5
                slave = 1 if count % 2 == 0 else 5
                os.write(fd, with_crc(bytes((slave, 3, 0, 0, 0, 2))))
            for fd in scm:
                os.write(fd, b"HELLO\r" if count % 3 else b"AB")
            count += 1
            time.sleep(0.1)
    finally:
        for client in clients:
            client.close()  # type: ignore[no-untyped-call]
        for fd in fds + scm:
            os.close(fd)


@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_an_example_plant_replays_identically(example: Path, tmp_path: Path) -> None:
    plant = free_port_plant(example, tmp_path / example.name)
    for program in example.parent.glob("*.pl7"):  # the programs the plant files name
        (tmp_path / program.name).write_text(program.read_text("utf-8"), "utf-8")
    record = tmp_path / "example.ftrec"
    run = start(plant, record)
    try:
        _stimulate(run)
    finally:
        run.stop()
    (tmp_path / example.name).unlink()  # the replay needs only the recording
    for program in tmp_path.glob("*.pl7"):
        program.unlink()
    result = fieldtwin("replay", str(record), cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith("identical: ")
    inputs = int(result.stdout.split()[1])
    if run.tcp or run.rtu_ptys or run.scm_ptys:
        assert inputs > 3, result.stdout  # the stimuli were recorded
