"""The console's ``prog`` commands: the PLC program, its state and its debugging.

    prog show                  the state, the active steps, where it is held, the source
    prog load FILE             load a PL7-3 program (a cold restart of the program);
                               the stand-alone console only, the file read with bounds
    prog load -                load the program text that comes with the line (the
                               control API's ``text``; the only form it takes)
    prog stop-at LABEL         hold at the end of the master task reaching a label
                               (SR1:L5, or L5 for the PRE)
    prog stop-at-step N        hold at the end of the master task activating step N
    prog step                  run one master task, then hold
    prog run                   let it run again
    prog clear                 forget every breakpoint

Internal objects are read and written with the usual ``read`` / ``write``
(``read W12 B3 X2``, ``write W20 5``).  See docs/console.md.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

from fieldtwin.errors import ConfigError
from fieldtwin.pl7 import Executor, Hit, format_program
from fieldtwin.textfile import MiB, read_text
from fieldtwin.tsx.plc import Plc

HELP = (
    "prog show | load FILE | load - (the program's text follows) | stop-at [SECTION:]LABEL"
    " | stop-at-step N | step | run | clear"
)
MAX_PROGRAM_BYTES = 1 * MiB  # a program file `prog load FILE` reads (docs/console.md)
TEXT_SOURCE = "<text>"  # how a program loaded from its text is named in messages
FILES_REFUSED = (
    "prog load: a file name is refused here: files are only for the stand-alone console"
    " (fieldtwin console PLANT); send the program's text instead:"
    ' {"line": "prog load -", "text": "..."} (fieldtwin console --attach does it for'
    " prog load FILE, reading FILE on its own side)"
)
INTERNAL = ("B", "X", "CW", "SY", "SW")  # read as numbers (W is the console's already)
_LABEL = re.compile(r"^(?:(PRE|POST|SR\d{1,3}):)?L(\d{1,3})$", re.IGNORECASE)
SOURCE_LINES = 40  # `prog show` prints at most this many lines of the program


def is_internal(name: str) -> bool:
    head = name.strip().upper()
    return head.startswith(INTERNAL) and head[-1:].isalnum() and any(c.isdigit() for c in head)


def load(plc: Plc, target: str, text: str | None, files: bool) -> list[str]:
    """``prog load FILE`` or ``prog load -`` with the program's ``text``."""
    if target != "-":
        if not files:
            raise ConfigError(FILES_REFUSED)
        text = read_text(Path(target), MAX_PROGRAM_BYTES, "PL7 program")
        source = target
    elif text is None:
        raise ConfigError(
            "prog load -: no program text came with the line (the control API's"
            ' "text"; in the stand-alone console, prog load FILE)'
        )
    else:
        source = TEXT_SOURCE
    # A str with a newline is a program's text to Plc.load_program, never a file name.
    loaded = plc.load_program(text if "\n" in text else text + "\n", source=source)
    shown = target if target != "-" else "the program text"
    return [f"loaded {shown}: {len(loaded.modules)} Literal sections", *state(plc)]


def prog_command(
    plc: Callable[[], Plc], *, files: bool = True
) -> Callable[[list[str], str | None], list[str]]:
    """The ``prog`` command of a console whose PLC ``plc()`` gives; it is given the
    line's words and the text that came with it.  ``files`` False refuses
    ``prog load FILE`` (the control API's console)."""

    def run(args: list[str], text: str | None = None) -> list[str]:
        if not args:
            raise ConfigError(f"prog: name a sub-command ({HELP})")
        verb, rest = args[0].lower(), args[1:]
        if text is not None and (verb != "load" or rest != ["-"]):
            raise ConfigError(
                f"prog {' '.join(args)}: takes no text after its line (only 'prog load -' does)"
            )
        the_plc = plc()
        if verb == "load":
            if len(rest) != 1:
                raise ConfigError(
                    "prog load: takes FILE, e.g. prog load examples/aem811_tank.pl7,"
                    " or - with the program's text"
                )
            return load(the_plc, rest[0], text, files)
        executor = the_plc.program
        if executor is None:
            raise ConfigError("prog: the PLC runs no program (prog load FILE, or [plc] program)")
        if verb == "show" and not rest:
            return [*state(the_plc), *source(executor)]
        if verb == "stop-at" and len(rest) == 1:
            match = _LABEL.match(rest[0])
            if match is None:
                raise ConfigError(f"prog stop-at: {rest[0]!r} is not a label (e.g. L5, SR1:L5)")
            section = (match.group(1) or "PRE").upper()
            executor.break_at_label(section, int(match.group(2)))
            return [f"stop at {section} L{int(match.group(2))}"]
        if verb == "stop-at-step" and len(rest) == 1:
            executor.break_at_step(rest[0].upper())
            return [f"stop at step {rest[0]}"]
        if verb == "step" and not rest:
            if executor.held is None:  # running: hold it here; the next step runs one task
                executor.held = Hit(executor.cycles)
                return state(the_plc)
            executor.resume()
            the_plc.advance(the_plc.scan_us / 1_000_000)  # one master task, bus and all
            if executor.held is None:
                executor.held = Hit(executor.cycles)
            return state(the_plc)
        if verb == "run" and not rest:
            executor.resume()
            return state(the_plc)
        if verb == "clear" and not rest:
            executor.clear_breakpoints()
            return ["breakpoints cleared"]
        raise ConfigError(f"prog: {' '.join(args)!r} not understood ({HELP})")

    return run


def state(plc: Plc) -> list[str]:
    executor = plc.program
    assert executor is not None
    if plc.fault is not None:
        mode = f"stopped (PLC in FAULT, {plc.fault})"
    elif not plc.running:
        mode = "stopped (PLC in STOP)"
    elif executor.held is not None:
        mode = f"held: {executor.held}"
    else:
        mode = "running"
    lines = [f"program {mode}, master task {executor.cycles}"]
    if executor.layout is not None:
        lines.append("active steps: " + (", ".join(executor.active_steps()) or "none"))
    lines.extend(f"fault: {f}" for f in list(executor.faults)[-3:])
    return lines


def source(executor: Executor) -> list[str]:
    """The program as the printer writes it; where it is held is marked ``>>``, and
    the listing starts a few lines above it."""
    text = format_program(executor.program).splitlines()
    held, start = executor.held, 0
    if held is not None and held.label is not None:
        section = next((k for k, line in enumerate(text) if line == f"%{held.module}"), 0)
        for k in range(section, len(text)):
            if text[k].startswith(f"!L{held.label} "):
                text[k] = ">> " + text[k]
                start = max(0, k - 5)
                break
    shown = text[start : start + SOURCE_LINES]
    more = len(text) - start - len(shown)
    return shown + ([f"... {more} more lines"] if more > 0 else [])
