"""``fieldtwin console --attach URL``: the console, run on a running plant.

Each command line goes to the plant's own Console through ``POST /console``
(fieldtwin.client): the output lines and the errors are the stand-alone
console's, and a script stops at its first error with status 2, naming the
line, as ``run_script`` does.  Interactive use is a plain prompt loop.

The plant reads no file for a request (docs/control.md, "Security"): here
``prog load FILE`` reads FILE on this side, with the bounds of the stand-alone
console, and sends its text (``prog load -``); a ``csv`` signal is refused by the
plant (it belongs in the plant file).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from fieldtwin.console_prog import TEXT_SOURCE
from fieldtwin.console_syntax import split_line
from fieldtwin.control.client import Client, ConsoleResult, ControlError
from fieldtwin.control.schemas import MAX_PROGRAM_TEXT
from fieldtwin.errors import ConfigError
from fieldtwin.textfile import read_text

PROMPT = "fieldtwin> "
LOADED_TEXT = "loaded the program text:"


def send(client: Client, line: str) -> ConsoleResult:
    """One line to the plant; ``prog load FILE`` goes as ``prog load -`` with FILE's
    text, read here (ConfigError if it cannot be), and answers as if FILE had been
    named: ``loaded FILE: ...``, ``FILE: line 3, column 5: ...``."""
    try:
        words = split_line(line)
    except ValueError:
        words = []  # the plant says what is wrong with the line
    if len(words) != 3 or [w.lower() for w in words[:2]] != ["prog", "load"] or words[2] == "-":
        return client.console(line)
    name = words[2]
    text = read_text(Path(name), MAX_PROGRAM_TEXT, "PL7 program")
    result = client.console("prog load -", text=text)
    lines = [
        f"loaded {name}:{shown.removeprefix(LOADED_TEXT)}"
        if shown.startswith(LOADED_TEXT)
        else shown
        for shown in result.lines
    ]
    error = result.error
    if error is not None and error.startswith(f"{TEXT_SOURCE}:"):
        error = name + error.removeprefix(TEXT_SOURCE)
    return ConsoleResult(lines, error)


def explain(exc: ControlError, client: Client) -> str:
    """The refusal as a console user acts on it: a 401 says to use ``--token``."""
    if exc.status == 401:
        if client.token is None:
            return (
                "this plant needs its control token: use --token TOKEN (the `control token:`"
                " line `fieldtwin run` printed)"
            )
        return "the token given with --token is not this plant's (see its `control token:` line)"
    return str(exc)


def run_remote(client: Client, lines: Iterable[str], out: TextIO, err: TextIO, source: str) -> int:
    """As fieldtwin.console.run_script, on the plant behind ``client``."""
    for number, line in enumerate(lines, start=1):
        if line.strip().lower() in ("quit", "exit"):
            break
        try:
            result = send(client, line)
        except (ControlError, ConfigError) as exc:
            out.flush()
            said = explain(exc, client) if isinstance(exc, ControlError) else str(exc)
            print(f"{source}:{number}: {line.strip()}: {said}", file=err)
            return 2
        for text in result.lines:
            print(text, file=out)
        if result.error is not None:
            out.flush()
            print(f"{source}:{number}: {line.strip()}: {result.error}", file=err)
            return 2
    return 0


def interactive(client: Client) -> int:
    """A prompt loop: errors are shown and the loop goes on; quit, exit or EOF end it."""
    plant = client.plant()
    print(f"attached to {plant['title']} at {client.url} (quit to leave; the plant runs on)")
    while True:
        try:
            line = input(PROMPT)
        except EOFError:
            print()
            return 0
        except KeyboardInterrupt:
            print()
            continue
        if line.strip().lower() in ("quit", "exit"):
            return 0
        try:
            result = send(client, line)
        except ConfigError as exc:
            print(f"error: {exc}", file=sys.stderr)
            continue
        except ControlError as exc:
            print(f"error: {explain(exc, client)}", file=sys.stderr)
            if exc.status in (0, 401):
                return 2
            continue
        for text in result.lines:
            print(text)
        if result.error is not None:
            print(f"error: {result.error}", file=sys.stderr)


__all__ = ["explain", "interactive", "run_remote", "send"]
