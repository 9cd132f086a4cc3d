"""README's console verbs and TES workbench sequence run as printed, in the order
printed, on the default plant (on free ports) and on a new parameter store."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

from tests.control.plantproc import ROOT, default_plant_copy

README = (ROOT / "README.md").read_text("utf-8")


def _section(title: str) -> str:
    start = README.index(f"## {title}")
    end = README.find("\n## ", start + 1)
    return README[start : end if end > 0 else None]


def _fieldtwin(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
        check=False,
    )


def console_verbs() -> list[str]:
    text = _section("The console")
    start = text.index("The same verbs work")
    end = text.index("with the input and fault names", start)
    return re.findall(r"`([^`]+)`", text[start:end])


def _verb_at(words: list[str]) -> int | None:
    for i in range(2, len(words)):
        if not words[i].startswith("-") and words[i - 1] not in ("--store", "--model", "--device"):
            return i
    return None


def tesis_sequence() -> list[list[str]]:
    """The workbench commands, `...` standing for the command before it up to its verb."""
    text = " ".join(_section("The TES workbench").split())
    commands: list[list[str]] = []
    prefix: list[str] = []
    for example in re.findall(r"`([^`]+)`", text):
        words = shlex.split(example)
        if words[0] == "...":
            words = prefix + words[1:]
        if words[:2] != ["fieldtwin", "tesis"]:
            continue
        verb_at = _verb_at(words)
        if verb_at is None:
            continue  # the command's name alone
        prefix = words[:verb_at]
        commands.append(words[1:])
    return commands


def test_the_console_verbs_run_on_the_default_plant(tmp_path: Path) -> None:
    verbs = console_verbs()
    assert "tes 2 input a2 4.5" in verbs and len(verbs) >= 5, verbs
    argv = ["console", str(default_plant_copy(tmp_path)), "--speed", "max"]
    for verb in verbs:
        argv += ["-c", verb]
    done = _fieldtwin(argv, tmp_path)
    assert done.returncode == 0, (verbs, done.stdout, done.stderr)


def test_the_tesis_sequence_runs_in_its_order(tmp_path: Path) -> None:
    commands = tesis_sequence()
    verbs = [
        (["fieldtwin", *command])[_verb_at(["fieldtwin", *command]) or 0] for command in commands
    ]
    assert verbs == ["models", "factory", "set", "show", "validate", "export"], commands
    for command in commands:
        done = _fieldtwin(command, tmp_path)
        assert done.returncode == 0, (command, done.stdout, done.stderr)
        assert done.stdout.strip(), command
    assert (tmp_path / "eeprom.toml").is_file()


def test_run_console_and_tesis_help_end_with_examples(tmp_path: Path) -> None:
    for command in ("run", "console", "tesis", "replay", "trace", "trace show"):
        done = _fieldtwin([*command.split(), "--help"], tmp_path)
        assert done.returncode == 0, done.stderr
        tail = done.stdout.rstrip().split("\nexamples:\n")[-1].splitlines()
        assert len(tail) >= 2 and all(line.startswith("  fieldtwin ") for line in tail), (
            command,
            done.stdout,
        )
    done = _fieldtwin(["diff", "--help"], tmp_path)
    assert done.stdout.rstrip().split("\nexamples:\n")[-1].startswith("  fieldtwin diff "), (
        command,
        done.stdout,
    )
