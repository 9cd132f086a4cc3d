"""The console's ``prog`` commands: the PLC program, its state and its debugging.

    prog show                  the state, the active steps, where it is held, the source
    prog load FILE             load a PL7-3 program (a cold restart of the program)
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
from fieldtwin.tsx.plc import Plc

HELP = "prog show | load FILE | stop-at [SECTION:]LABEL | stop-at-step N | step | run | clear"
INTERNAL = ("B", "X", "CW", "SY", "SW")  # read as numbers (W is the console's already)
_LABEL = re.compile(r"^(?:(PRE|POST|SR\d{1,3}):)?L(\d{1,3})$", re.IGNORECASE)
SOURCE_LINES = 40  # `prog show` prints at most this many lines of the program


def is_internal(name: str) -> bool:
    head = name.strip().upper()
    return head.startswith(INTERNAL) and head[-1:].isalnum() and any(c.isdigit() for c in head)


def prog_command(plc: Callable[[], Plc]) -> Callable[[list[str]], list[str]]:
    """The ``prog`` command of a console whose PLC ``plc()`` gives."""

    def run(args: list[str]) -> list[str]:
        if not args:
            raise ConfigError(f"prog: name a sub-command ({HELP})")
        verb, rest = args[0].lower(), args[1:]
        the_plc = plc()
        if verb == "load":
            if len(rest) != 1:
                raise ConfigError("prog load: takes FILE, e.g. prog load examples/aem811_tank.pl7")
            loaded = the_plc.load_program(Path(rest[0]))
            return [f"loaded {rest[0]}: {len(loaded.modules)} Literal sections", *state(the_plc)]
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
    if not plc.running:
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
