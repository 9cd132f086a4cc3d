"""No request reads a file (docs/control.md, "Security"): the control API's console
refuses every command that names one, and no answer carries anything of a file.

In-process (the Control the routes call, on simulated time); the black-box test of
the same through a real `fieldtwin run` and `console --attach` is at the end.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from fieldtwin.clock import S
from fieldtwin.control.resources import Control, refuse_files
from fieldtwin.errors import ConfigError
from fieldtwin.plant import Plant, load_plant
from fieldtwin.runtime.door import Command
from fieldtwin.runtime.runner import Runner
from fieldtwin.signals.spec import file_in_spec
from tests.control.plantproc import ROOT, default_plant_copy, fieldtwin_run

MARKER = "MARKER-7f3a9c-do-not-echo"
PROGRAM = "%PRE\n!     30->W20\n"  # one Literal section: W20 = 30 at every master task


@pytest.fixture(scope="module")
def secret(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A file the process can read whose every line carries the marker; as CSV its
    first line is a bad row (its content would be quoted by a careless message)."""
    path = tmp_path_factory.mktemp("secret") / "secret.csv"
    path.write_text(f"{MARKER},{MARKER}\n0,1\n{MARKER}\n%PRE\n! {MARKER}\n")
    return path


@pytest.fixture(scope="module")
def control(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Control]:
    plant: Plant = load_plant(default_plant_copy(tmp_path_factory.mktemp("plant")), speed=None)
    yield Control(plant, Runner(plant.clock, None), plant.events)
    plant.close()


def refused(control: Control, line: str, text: str | None = None) -> str:
    answer = control.console_line(line, text)
    shown = json.dumps(answer)
    assert MARKER not in shown, shown
    assert "root:" not in shown, shown  # nothing of /etc/passwd either
    assert answer["lines"] == [], answer
    assert isinstance(answer["error"], str), answer
    return answer["error"]


@pytest.mark.parametrize(
    ("line", "verb"),
    [
        ("signal 5 0 csv file=/etc/passwd", "signal 5 0"),
        ("signal 5 0 csv file={secret}", "signal 5 0"),
        ("signal 5 0 CSV file={secret}", "signal 5 0"),
        ("tes 2 signal a0 csv file={secret}", "tes 2 signal a0"),
        ("signal 5 0 sine amplitude=1 period_s=2 file={secret}", "signal 5 0.file"),
        ("signal 5 0 sine amplitude=1 period_s=2 path={secret}", "signal 5 0.path"),
        ("signal 5 0 pwl points_file={secret}", "signal 5 0.points_file"),
    ],
)
def test_a_signal_that_reads_a_file_is_refused_naming_the_verb(
    control: Control, secret: Path, line: str, verb: str
) -> None:
    error = refused(control, line.format(secret=secret))
    assert error.startswith(verb), error
    assert "reads a file" in error and "only for the stand-alone console" in error


@pytest.mark.parametrize("name", ["/etc/passwd", "{secret}", "/dev/zero", "relative.pl7"])
def test_prog_load_of_a_file_is_refused_and_says_how_to_send_the_text(
    control: Control, secret: Path, name: str
) -> None:
    error = refused(control, f"prog load {name.format(secret=secret)}")
    assert error.startswith("prog load: a file name is refused here"), error
    assert "only for the stand-alone console" in error
    assert '{"line": "prog load -", "text": "..."}' in error


def test_prog_load_takes_the_program_text(control: Control) -> None:
    answer = control.console_line("prog load -", PROGRAM)
    assert answer["error"] is None, answer
    assert answer["lines"][0] == "loaded the program text: 1 Literal sections"
    started = control.console_line("advance 50ms")  # a runner mode through the API
    assert started["lines"][0].startswith("advancing to t = "), started
    ended = control.take_console_mode()
    assert ended is not None
    assert control.runner.run_until(ended.done, 10 * S)
    assert control.console_mode_answer(ended.result())["lines"][0].startswith("t = ")
    assert control.console_line("W20") == {"lines": ["W20 = 30"], "error": None}
    # the text may also follow the line's first newline (how it is recorded)
    assert control.console_line("prog load -\n" + PROGRAM)["error"] is None


def test_the_text_is_recorded_with_its_line_and_replays(control: Control) -> None:
    recorded: list[str] = []

    class Recorder:  # as runtime.record.Recorder: sees the door's commands
        def before(self, command: Command) -> None:
            assert command.kind == "line"
            recorded.append(command.name)

        def after(self, command: Command, answer: object, error: BaseException | None) -> None:
            assert error is None

    plant = control.plant
    stop = plant.door.watch(Recorder())
    try:
        answer = control.console_line("prog load -", PROGRAM)
    finally:
        stop()
    assert recorded == ["prog load -\n" + PROGRAM]
    assert control.console.execute(recorded[0]) == answer["lines"]  # what a replay runs


def test_a_refused_program_text_names_line_and_column_of_the_text(control: Control) -> None:
    error = control.console_line("prog load -", "%PRE\n! bogus\n")["error"]
    assert isinstance(error, str) and error.startswith("<text>: line 2, column 3: 'bogus'")


@pytest.mark.parametrize(
    ("line", "text", "message"),
    [
        ("prog load -", None, "prog load -: no program text came with the line"),
        ("prog load -", "  \n", "prog load -: no program text came with the line"),
        ("prog show", PROGRAM, "prog show: takes no text after its line"),
        ("advance 1", PROGRAM, "'advance 1': takes no text after its line"),
        ("advance 1\n%PRE", None, "'advance 1': takes no text after its line"),
        ("prog load -\n%PRE", PROGRAM, "not both"),
        ("prog load {secret}", PROGRAM, "takes no text after its line"),
    ],
)
def test_text_comes_with_prog_load_dash_only(
    control: Control, secret: Path, line: str, text: str | None, message: str
) -> None:
    assert message in refused(control, line.format(secret=secret), text)


def test_the_inputs_route_refuses_a_file_anywhere_in_the_table() -> None:
    nested = {"kind": "sum", "terms": [1.0, {"kind": "csv", "file": "x.csv"}]}
    assert file_in_spec(nested, "s") == "s.terms[1]: kind 'csv'"
    assert file_in_spec({"kind": "noise", "base": {"path": "p"}}, "s") == "s.base.path: a file name"
    assert file_in_spec({"kind": "sine", "amplitude": 1, "period_s": 1}, "s") is None
    with pytest.raises(ConfigError, match=r"^in\.signal\.terms\[1\]: kind 'csv' reads a file"):
        refuse_files(nested, "in.signal")


# --- black-box: a real `fieldtwin run`, its HTTP API and `console --attach` -------------


def test_a_running_plant_reads_no_file_for_a_request(tmp_path: Path, secret: Path) -> None:
    program = tmp_path / "w20.pl7"
    program.write_text(PROGRAM)
    with fieldtwin_run(default_plant_copy(tmp_path)) as plant:
        http = httpx.Client(base_url=plant.url, timeout=30)
        for line in (
            "signal 5 0 csv file=/etc/passwd",
            "prog load /etc/passwd",
            f"signal 5 0 csv file={secret}",
            f"prog load {secret}",
        ):
            reply = http.post("/console", json={"line": line})
            assert reply.status_code == 200, reply.text
            assert reply.json()["error"] and reply.json()["lines"] == []
            assert MARKER not in reply.text and "root:" not in reply.text, reply.text
        loaded = http.post("/console", json={"line": "prog load -", "text": PROGRAM}).json()
        assert loaded["error"] is None, loaded
        too_long = http.post("/console", json={"line": "prog load -", "text": "x" * 60_000})
        assert too_long.status_code in (413, 422)

        def attached(*commands: str) -> subprocess.CompletedProcess[str]:
            args = [a for c in commands for a in ("-c", c)]
            return subprocess.run(
                [sys.executable, "-m", "fieldtwin", "console", "--attach", plant.url, *args],
                capture_output=True,
                text=True,
                timeout=60,
                cwd=ROOT,
                check=False,
            )

        # --attach reads FILE on its own side and sends the text: the stand-alone output
        done = attached(f"prog load {program}", "advance 50ms", "W20")
        assert done.returncode == 0, done.stderr
        assert done.stdout.splitlines()[0] == f"loaded {program}: 1 Literal sections"
        assert done.stdout.splitlines()[-1] == "W20 = 30"
        bad = tmp_path / "bad.pl7"
        bad.write_text("%PRE\n! bogus\n")
        done = attached(f"prog load {bad}")
        assert done.returncode == 2
        assert f"-c:1: prog load {bad}: {bad}: line 2, column 3: 'bogus'" in done.stderr
        done = attached(f"signal 5 0 csv file={secret}")
        assert done.returncode == 2 and "Traceback" not in done.stderr
        assert "only for the stand-alone console" in done.stderr
        assert MARKER not in done.stdout + done.stderr
        done = attached("prog load /dev/zero")
        assert done.returncode == 2 and "Traceback" not in done.stderr
        assert "/dev/zero: a character device, not a regular file" in done.stderr
        assert plant.alive()
