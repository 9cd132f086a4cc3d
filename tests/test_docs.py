"""The documentation tells the truth: README.md, docs/*.md and examples/*.toml.

* every ``$ fieldtwin console ...`` / ``$ fieldtwin run ...`` transcript in a code
  block prints exactly the output shown under it (the real command, as a subprocess);
* every TOML code block that is a plant (it has ``[plc]``, ``[[module]]`` or
  ``[[tes]]``) loads with ``load_plant`` and runs 15 simulated seconds in the console;
  the signal lines of docs/signals.md build with ``signal_from_spec``;
* every example plant loads and runs 15 simulated seconds without error;
* the Python blocks of the pages that show complete programs run;
* the error messages the pages quote are the ones the product gives.

Every subprocess is bounded by a timeout.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.signals import signal_from_spec
from fieldtwin.tsx.addressing import parse_object

ROOT = Path(__file__).resolve().parent.parent
DOCS = sorted((ROOT / "docs").glob("*.md"))
PAGES = [ROOT / "README.md", *DOCS]
EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))
PLC_EXAMPLES = [e for e in EXAMPLES if e.name != "tes.toml"]  # tes.toml: tests/hardening
TIMEOUT_S = 120
PLANT_TABLES = {"plc", "module", "tes"}
# Pages whose Python blocks are whole programs (the others show fragments that need
# a serial device, a peer or a run_forever loop).
RUNNABLE_PYTHON = ("README.md", "aem811.md", "dem24.md", "objects.md", "signals.md", "tes.md")
# `--speed max` is what the pages show: the transcripts run as printed.
SPEED_FOR_TESTS = "max"


@dataclass(frozen=True, slots=True)
class Block:
    page: Path
    lang: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.page.name}: {self.text.splitlines()[0][:60] if self.text else ''}"


def code_blocks(page: Path) -> list[Block]:
    pattern = re.compile(r"^```([\w+-]*)\n(.*?)^```", re.S | re.M)
    return [Block(page, m.group(1), m.group(2)) for m in pattern.finditer(page.read_text())]


def all_blocks(lang: str) -> list[Block]:
    return [b for page in PAGES for b in code_blocks(page) if b.lang == lang]


def ids(blocks: list[Block]) -> list[str]:
    return [f"{b.page.name}[{i}]" for i, b in enumerate(blocks)]


def fieldtwin(
    args: list[str], *, cwd: Path = ROOT, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, COLUMNS="200")
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *args],
        cwd=cwd,
        input=stdin if stdin is not None else "",
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        env=env,
    )


# ---------------------------------------------------------------- transcripts


@dataclass(frozen=True, slots=True)
class Transcript:
    block: Block
    argv: list[str]
    stdin: str | None
    expected: list[str]


def transcript(block: Block) -> Transcript | None:
    lines = block.text.splitlines()
    if not lines or not lines[0].startswith("$ fieldtwin "):
        return None
    command, rest = lines[0][2:], lines[1:]
    stdin = None
    heredoc = re.search(r"<<'(\w+)'$", command)
    if heredoc:
        end = rest.index(heredoc.group(1))
        stdin = "\n".join(rest[:end]) + "\n"
        command, rest = command[: heredoc.start()], rest[end + 1 :]
    return Transcript(block, shlex.split(command)[1:], stdin, rest)


TRANSCRIPTS = [t for b in all_blocks("") for t in [transcript(b)] if t is not None]


def test_the_pages_show_transcripts() -> None:
    pages = {t.block.page.name for t in TRANSCRIPTS}
    assert {"README.md", "console.md", "plant.md"} <= pages


@pytest.mark.parametrize("case", TRANSCRIPTS, ids=[t.block.where for t in TRANSCRIPTS])
def test_transcript_prints_what_the_page_shows(case: Transcript) -> None:
    assert case.argv[0] in ("console", "run"), case.block.where
    argv = case.argv
    if argv[0] == "console":
        argv = [SPEED_FOR_TESTS if a == "max" else a for a in argv]
    done = fieldtwin(argv, stdin=case.stdin)
    assert done.stdout.splitlines() == case.expected, done.stderr
    if done.returncode != 0:
        # a failing transcript: the page quotes the error it prints
        assert done.returncode == 2
        message = done.stderr.strip().split(" (allowed")[0]
        assert message and message in case.block.page.read_text(), done.stderr


# ---------------------------------------------------------------- TOML blocks


TOML_BLOCKS = all_blocks("toml")


def is_signal_list(text: str) -> bool:
    """docs/signals.md lists one signal table a line, all under the key `signal`."""
    return all(line.startswith("signal = ") for line in text.splitlines() if line.strip())


def is_plant(text: str) -> bool:
    return not is_signal_list(text) and bool(PLANT_TABLES & set(tomllib.loads(text)))


PLANT_BLOCKS = [b for b in TOML_BLOCKS if is_plant(b.text)]


@pytest.mark.parametrize("block", TOML_BLOCKS, ids=ids(TOML_BLOCKS))
def test_toml_block_is_toml(block: Block) -> None:
    lines = block.text.splitlines() if is_signal_list(block.text) else [block.text]
    for text in lines:
        tomllib.loads(text)


def test_every_page_with_plant_keys_shows_a_whole_plant() -> None:
    pages = {b.page.name for b in PLANT_BLOCKS}
    assert {"README.md", "plant.md", "aem811.md", "dem24.md", "scm.md", "tes.md"} <= pages


@pytest.mark.parametrize("block", PLANT_BLOCKS, ids=ids(PLANT_BLOCKS))
def test_plant_block_loads_and_runs(block: Block, tmp_path: Path) -> None:
    plant_file = tmp_path / "plant.toml"
    plant_file.write_text(block.text)
    plant = load_plant(plant_file)
    look = ["-c", "status"] if plant.plc is not None else []
    for tes in plant.tes:
        look += ["-c", f"tes {tes.slave} read H'000'"]
    assert look, "a plant with neither modules nor TES"
    done = fieldtwin(
        ["console", "plant.toml", "--speed", SPEED_FOR_TESTS, "-c", "advance 15", *look],
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "t = 15.000 s"


def signal_lines() -> list[str]:
    page = ROOT / "docs" / "signals.md"
    return [
        line
        for b in code_blocks(page)
        if b.lang == "toml"
        for line in b.text.splitlines()
        if line.startswith("signal = ")
    ]


def test_signal_page_lines_build(tmp_path: Path) -> None:
    csv_blocks = [b for b in code_blocks(ROOT / "docs" / "signals.md") if b.lang == "csv"]
    (tmp_path / "level.csv").write_text(csv_blocks[0].text)
    lines = signal_lines()
    assert len(lines) >= 14
    for line in lines:
        spec = tomllib.loads(line)["signal"]
        signal = signal_from_spec(spec, where="signals.md", base_dir=tmp_path)
        signal.value_at(11_000_000)


# ---------------------------------------------------------------- examples


@pytest.mark.parametrize("example", PLC_EXAMPLES, ids=[e.name for e in PLC_EXAMPLES])
def test_example_plant_loads_and_runs_15_seconds(example: Path) -> None:
    plant = load_plant(example)
    assert plant.plc is not None
    done = fieldtwin(
        ["console", str(example), "--speed", SPEED_FOR_TESTS, "-c", "advance 15", "-c", "status"]
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    lines = done.stdout.splitlines()
    assert lines[0] == "t = 15.000 s"
    assert "state: operational" in lines


def test_example_aem811_does_what_its_comments_say() -> None:
    done = fieldtwin(
        [
            "console",
            "examples/aem811.toml",
            "--speed",
            SPEED_FOR_TESTS,
            *("-c", "advance 15", "-c", "read IW5,0,C IW5,2,D I5,S"),
            *("-c", "write OW5,0,C 0", "-c", "advance 1", "-c", "read IW5,0,C"),
            *("-c", "power break 2", "-c", "advance 12", "-c", "read IW5,2,D"),
        ]
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    assert out[1:4] == ["IW5,0,C = 1", "IW5,2,D = 0", "I5,S = 0"]  # configured, in Run
    assert "IW5,0,C = 0" in out  # stopped by the PLC
    assert out[-1] == "IW5,2,D = 1"  # the power break lost the configuration


def test_example_dem24_logs_once_channels_are_selected() -> None:
    done = fieldtwin(
        [
            "console",
            "examples/dem24.toml",
            "--speed",
            SPEED_FOR_TESTS,
            *("-c", "advance 15", "-c", "OW4,2 = H'FFFF'", "-c", "advance 70"),
            *("-c", "read I4,0", "-c", "exchange H'0400' 1 send 7 9 recv 234"),
        ]
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    assert "I4,0 = 1" in out  # ready to log: time set, pulses received
    assert "TXT0,V = H'0081'  TXT0,S = 234  TXT0,E = 0" in out  # nine 26-byte messages


def test_example_scm_request_in_its_comment_is_accepted() -> None:
    # examples/scm.toml: `exchange H'0700' 1 text "HELLO"` sends on the configured channel
    done = fieldtwin(
        [
            "console",
            "examples/scm.toml",
            "--speed",
            SPEED_FOR_TESTS,
            *("-c", "advance 2", "-c", "exchange H'0700' 1 text \"HELLO\""),
        ]
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "TXT0,V = H'0000'  TXT0,S = 0  TXT0,E = 0"
    text = (ROOT / "examples" / "scm.toml").read_text()
    assert "exchange H'0700' 4 send 20 recv 20" in text
    assert "exchange H'0700' 1 text \"HELLO\"" in text


# ---------------------------------------------------------------- Python blocks


PYTHON_BLOCKS = [
    b for b in all_blocks("python") if b.page.name in RUNNABLE_PYTHON and ">>>" not in b.text
]


@pytest.mark.parametrize("block", PYTHON_BLOCKS, ids=ids(PYTHON_BLOCKS))
def test_python_block_runs(block: Block, tmp_path: Path) -> None:
    if block.page.name == "signals.md":  # the CSV the block reads, from the same page
        csv = next(b for b in code_blocks(block.page) if b.lang == "csv")
        (tmp_path / "flow.csv").write_text(csv.text)
    done = subprocess.run(
        [sys.executable, "-c", block.text],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert done.returncode == 0, done.stderr


# ---------------------------------------------------------------- quoted errors


def test_objects_page_refused_names() -> None:
    block = next(b for b in code_blocks(ROOT / "docs" / "objects.md") if "QW5,0" in b.text)
    for line in block.text.splitlines():
        name = line.split("'")[1]
        with pytest.raises(ConfigError) as caught:
            parse_object(name)
        assert str(caught.value) == line


def test_signals_page_errors() -> None:
    where = "plant.toml: module[0].inputs[3].signal"
    specs: list[dict[str, object]] = [
        {"kind": "sinus"},
        {"kind": "sine", "amplitude": 1, "period": 1},
        {"kind": "square", "low": 0, "high": 1, "period_s": 1, "duty": 2.0},
    ]
    page = (ROOT / "docs" / "signals.md").read_text()
    for spec in specs:
        with pytest.raises(ConfigError) as caught:
            signal_from_spec(spec, where=where, base_dir=ROOT)
        assert f"\n{caught.value}\n" in page


PLANT_ERRORS = [
    '[plc]\nmodel = "TSX 99"\n',
    '[plc]\nmodel = "TSX 47-20"\n'
    '[[module]]\ntype = "TSX AEM 811"\nslot = 2\n'
    '[[module]]\ntype = "TSX AEM 811"\nslot = 4\n',
    '[[module]]\ntype = "TSX AEM 811"\nslot = 5\ncolour = "red"\n',
]


@pytest.mark.parametrize("text", PLANT_ERRORS)
def test_plant_page_errors(text: str, tmp_path: Path) -> None:
    (tmp_path / "plant.toml").write_text(text)
    done = fieldtwin(["console", "plant.toml", "-c", "time"], cwd=tmp_path)
    assert done.returncode == 2
    assert done.stdout == ""
    assert f"\n{done.stderr.strip()}\n" in (ROOT / "docs" / "plant.md").read_text()
