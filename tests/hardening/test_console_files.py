"""The stand-alone console keeps its files, read with bounds (fieldtwin.textfile):
regular files only (a FIFO never blocks, /dev/zero never grows memory), a documented
size, UTF-8 with a clear error; a CSV error never quotes the file (issue 20, R3)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fieldtwin.console import Console
from fieldtwin.console_prog import MAX_PROGRAM_BYTES
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.signals.table import MAX_FILE_BYTES
from fieldtwin.textfile import read_text

ROOT = Path(__file__).resolve().parents[2]
MARKER = "MARKER-51c0de-never-shown"
PLANT = """[plc]
model = "TSX 87"
[[module]]
type = "TSX AEM 811"
slot = 5
"""


@pytest.fixture
def console(tmp_path: Path) -> Console:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT)
    return Console(load_plant(path))


def refused(console: Console, line: str) -> str:
    with pytest.raises(ConfigError) as info:
        console.execute(line)
    return str(info.value)


@pytest.mark.timeout(30)
def test_a_fifo_is_refused_without_blocking(console: Console, tmp_path: Path) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)  # nobody writes: an open that waits would never return
    message = f"{fifo}: a FIFO, not a regular file"
    assert message in refused(console, f"prog load {fifo}")
    assert message in refused(console, f"signal 5 0 csv file={fifo}")


def test_devices_and_directories_are_refused_before_a_byte_is_read(
    console: Console, tmp_path: Path
) -> None:
    assert "/dev/zero: a character device, not a regular file" in refused(
        console, "prog load /dev/zero"
    )
    assert "/dev/zero: a character device" in refused(console, "signal 5 0 csv file=/dev/zero")
    assert f"{tmp_path}: a directory" in refused(console, f"prog load {tmp_path}")


def test_a_file_over_the_limit_is_refused_by_its_size(console: Console, tmp_path: Path) -> None:
    big = tmp_path / "big.pl7"
    with big.open("wb") as file:  # sparse: no disk, and never read
        file.truncate(MAX_PROGRAM_BYTES + 1)
    error = refused(console, f"prog load {big}")
    assert f"{big}: larger than 1 MiB (allowed: a regular PL7 program of at most 1 MiB" in error
    csv = tmp_path / "big.csv"
    with csv.open("wb") as file:
        file.truncate(MAX_FILE_BYTES + 1)
    assert f"{csv}: larger than 16 MiB" in refused(console, f"signal 5 0 csv file={csv}")


def test_a_file_that_is_not_utf8_names_its_line(console: Console, tmp_path: Path) -> None:
    program = tmp_path / "latin1.pl7"
    program.write_bytes(b"%PRE\n<caf\xe9\n!     30->W20\n")
    error = refused(console, f"prog load {program}")
    assert error.startswith(f"{program}:2: not a UTF-8 text file (byte 9;"), error
    csv = tmp_path / "latin1.csv"
    csv.write_bytes(b"0,1\n\xff\xfe,2\n")
    assert f"{csv}:2: not a UTF-8 text file" in refused(console, f"signal 5 0 csv file={csv}")


@pytest.mark.parametrize(
    ("content", "where"),
    [
        (f"{MARKER}\n0,1\n", ":1: 1 column, not 2"),
        (f"0,1\n{MARKER},2\n", ":2: column 1 (time_s) is not a finite number"),
        (f"0,1\n1,{MARKER}\n", ":2: column 2 (value) is not a finite number"),
        (f"0,1\n1,2,{MARKER}\n", ":2: 3 columns, not 2"),
    ],
)
def test_a_csv_error_names_file_and_line_never_the_content(
    console: Console, tmp_path: Path, content: str, where: str
) -> None:
    csv = tmp_path / "secret.csv"
    csv.write_text(content)
    error = refused(console, f"signal 5 0 csv file={csv}")
    assert f"signal 5 0: {csv}{where}" in error, error
    assert MARKER not in error


def test_files_within_bounds_still_load(console: Console, tmp_path: Path) -> None:
    program = tmp_path / "w20.pl7"
    program.write_bytes("\ufeff%PRE\n<réglage\n!     30->W20\n".encode())  # a BOM is dropped
    assert console.execute(f"prog load {program}")[0] == f"loaded {program}: 1 Literal sections"
    console.execute("advance 50ms")
    assert console.execute("W20") == ["W20 = 30"]
    csv = tmp_path / "level.csv"
    csv.write_text("time_s,mA\n0,4\n10,20\n")
    assert console.execute(f"signal 5 0 csv file={csv}") == ["signal 5 0 = csv"]


def test_read_text_reports_what_it_cannot_read(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"missing\.txt: cannot read the thing \(No such file"):
        read_text(tmp_path / "missing.txt", 10, "thing")
    exact = tmp_path / "ten.txt"
    exact.write_text("0123456789")
    assert read_text(exact, 10, "thing") == "0123456789"
    with pytest.raises(ConfigError, match=r"larger than 9 bytes \(allowed: a regular thing of"):
        read_text(exact, 9, "thing")


@pytest.mark.timeout(60)
def test_the_console_command_line_ends_with_status_2_and_no_traceback(tmp_path: Path) -> None:
    plant = tmp_path / "plant.toml"
    plant.write_text(PLANT)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    latin = tmp_path / "latin1.pl7"
    latin.write_bytes(b"%PRE\n<caf\xe9\n")
    secret = tmp_path / "secret.csv"
    secret.write_text(f"{MARKER}\n")
    for line, needle in (
        (f"prog load {fifo}", "a FIFO, not a regular file"),
        ("prog load /dev/zero", "a character device, not a regular file"),
        (f"prog load {latin}", "not a UTF-8 text file"),
        (f"signal 5 0 csv file={secret}", ":1: 1 column, not 2"),
    ):
        done = subprocess.run(
            [sys.executable, "-m", "fieldtwin", "console", str(plant), "-c", line],
            capture_output=True,
            text=True,
            timeout=30,
            cwd=ROOT,
            check=False,
        )
        assert done.returncode == 2, (line, done.stdout, done.stderr)
        assert "Traceback" not in done.stderr and needle in done.stderr, done.stderr
        assert MARKER not in done.stdout + done.stderr
