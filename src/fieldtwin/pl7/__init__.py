"""PL7-3 programs: parse, check, print, and run them once per master task.

    program = parse(text)            # tree (fieldtwin.pl7.tree), Pl7Error if refused
    check(program)                   # names, labels, SRs, chart consistency
    format_program(program)          # back to source
    executor = Executor(program, InMemory())
    executor.run_master_task()

See docs/pl7.md.  The package is sans-IO: it never reads a clock or a file.
"""

from fieldtwin.pl7.checker import Limits, check
from fieldtwin.pl7.errors import Pl7Error, ProgramFault
from fieldtwin.pl7.executor import FAULT_BIT, Executor, FaultRecord, Hit
from fieldtwin.pl7.memory import InMemory, ProgramMemory, Started
from fieldtwin.pl7.parser import parse
from fieldtwin.pl7.printer import format_program

__all__ = [
    "FAULT_BIT",
    "Executor",
    "FaultRecord",
    "Hit",
    "InMemory",
    "Limits",
    "Pl7Error",
    "ProgramFault",
    "ProgramMemory",
    "Started",
    "check",
    "format_program",
    "parse",
]
