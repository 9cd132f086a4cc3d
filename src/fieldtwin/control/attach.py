"""``fieldtwin console --attach URL``: the console, run on a running plant.

Each command line goes to the plant's own Console through ``POST /console``
(fieldtwin.client): the output lines and the errors are the stand-alone
console's, and a script stops at its first error with status 2, naming the
line, as ``run_script`` does.  Interactive use is a plain prompt loop.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TextIO

from fieldtwin.control.client import Client, ControlError

PROMPT = "fieldtwin> "


def run_remote(client: Client, lines: Iterable[str], out: TextIO, err: TextIO, source: str) -> int:
    """As fieldtwin.console.run_script, on the plant behind ``client``."""
    for number, line in enumerate(lines, start=1):
        if line.strip().lower() in ("quit", "exit"):
            break
        try:
            result = client.console(line)
        except ControlError as exc:
            out.flush()
            print(f"{source}:{number}: {line.strip()}: {exc}", file=err)
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
            result = client.console(line)
        except ControlError as exc:
            print(f"error: {exc}", file=sys.stderr)
            if exc.status == 0:
                return 2
            continue
        for text in result.lines:
            print(text)
        if result.error is not None:
            print(f"error: {result.error}", file=sys.stderr)


__all__ = ["interactive", "run_remote"]
