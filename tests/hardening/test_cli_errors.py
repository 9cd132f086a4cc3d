"""What used to end in a traceback now ends with status 2 and a clear error (issue 10 item 6)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def fieldtwin(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *args],
        cwd=cwd,
        input="",
        capture_output=True,
        text=True,
        timeout=60,
        env=dict(os.environ, COLUMNS="120"),
    )


def _refused(done: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    assert "Traceback" not in done.stderr, done.stderr
    for needle in needles:
        assert needle in done.stderr, done.stderr


PLC = '[plc]\nmodel = "TSX 87"\n'
TES = '[[tes]]\nmodel = "TES 8EA"\nslave = 2\nendpoint = "tcp://127.0.0.1:0"\n'

CASES = {
    "non_utf8": (b"# \xff\n" + PLC.encode(), ["plant.toml", "UTF-8"]),
    "model_list": (b'[plc]\nmodel = ["TSX 87"]\n', ["plant.toml", "plc.model"]),
    "link_list": ((TES + 'link = ["rs485"]\n').encode(), ["plant.toml", "tes[0].link"]),
    "baud_superscript": (
        TES.replace("tcp://127.0.0.1:0", "pty?baud=²").encode(),
        ["plant.toml", "tes[0].endpoint"],
    ),
    "nested_arrays": (b"x = " + b"[" * 10000 + b"]" * 10000 + b"\n", ["plant.toml"]),
    "speed_huge": (PLC.encode() + b"[run]\nspeed = 1e308\n", ["plant.toml", "run.speed"]),
}


@pytest.mark.parametrize("command", ["run", "console"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_plant_file_is_a_clear_error(case: str, command: str, tmp_path: Path) -> None:
    text, needles = CASES[case]
    (tmp_path / "plant.toml").write_bytes(text)
    extra = ["--no-live", "--duration", "1"] if command == "run" else ["-c", "time"]
    _refused(fieldtwin([command, "plant.toml", *extra], tmp_path), *needles)


def test_speed_overflow_on_the_command_line(tmp_path: Path) -> None:
    (tmp_path / "plant.toml").write_text(PLC)
    done = fieldtwin(
        ["run", "plant.toml", "--no-live", "--duration", "1", "--speed", "1e308"], tmp_path
    )
    _refused(done, "--speed")


def test_a_console_script_that_is_not_utf8(tmp_path: Path) -> None:
    (tmp_path / "plant.toml").write_text(PLC)
    (tmp_path / "script.txt").write_bytes(b"time\n# \xff\n")
    done = fieldtwin(["console", "plant.toml", "--script", "script.txt"], tmp_path)
    _refused(done, "script.txt", "UTF-8")


def test_an_invalid_plant_speed_is_reported_even_with_speed_given(tmp_path: Path) -> None:
    # issue 10 item 21: an invalid [run] speed was not reported when --speed was given
    (tmp_path / "plant.toml").write_text(PLC + '[run]\nspeed = "fast"\n')
    done = fieldtwin(
        ["run", "plant.toml", "--no-live", "--duration", "1", "--speed", "10"], tmp_path
    )
    _refused(done, "run.speed")


def test_speed_words_other_than_max_are_refused(tmp_path: Path) -> None:
    # issue 10 item 21: `--speed fast` was silently taken as max
    (tmp_path / "plant.toml").write_text(PLC)
    done = fieldtwin(
        ["run", "plant.toml", "--no-live", "--duration", "1", "--speed", "fast"], tmp_path
    )
    _refused(done, "--speed", "'fast'")


def test_run_with_a_duration_ends_with_the_final_status(tmp_path: Path) -> None:
    # issue 10 item 21: `fieldtwin run --duration` printed no final status line
    example = str(ROOT / "examples" / "aem811.toml")
    done = fieldtwin(["run", example, "--no-live", "--duration", "3", "--speed", "max"], tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[-3:-1] == ["t = 3.000 s", lines[-2]] and lines[-2].startswith(
        "slot 5 TSX AEM 811:"
    )
    assert lines[-1] == "stopped at t = 3.000 s"


def test_a_console_script_or_plant_that_is_a_fifo_is_refused_without_blocking(
    tmp_path: Path,
) -> None:
    (tmp_path / "plant.toml").write_text(PLC)
    os.mkfifo(tmp_path / "script.fifo")
    done = fieldtwin(["console", "plant.toml", "--script", "script.fifo"], tmp_path)
    _refused(done, "script.fifo", "a FIFO, not a regular file")
    os.mkfifo(tmp_path / "plant.fifo")
    done = fieldtwin(["run", "plant.fifo", "--no-live", "--duration", "1"], tmp_path)
    _refused(done, "plant.fifo", "a FIFO, not a regular file")
