"""Errors of PL7-3 programs.

A refused program is the user's mistake: :class:`Pl7Error` (a ConfigError) names
the line, the column, the token and what was expected.  A fault while the program
runs (an index out of its table, a Text Block misuse, a loop past its bound) is
:class:`ProgramFault`: the executor catches it, records it and sets the program
error bit; it never leaves the master task.
"""

from __future__ import annotations

from fieldtwin.errors import ConfigError, FieldtwinError


class Pl7Error(ConfigError):
    """A program refused at load: where, which token, what was expected."""

    def __init__(self, line: int, column: int, token: str, expected: str, source: str = "") -> None:
        self.line = line
        self.column = column
        self.token = token
        self.expected = expected
        self.source = source
        where = f"{source}: " if source else ""
        shown = "end of file" if token == "" else repr(token)
        super().__init__(f"{where}line {line}, column {column}: {shown}: expected {expected}")


class ProgramFault(FieldtwinError):
    """A run-time error of the program (caught by the executor, never raised out of it)."""


class WatchdogOverrun(FieldtwinError):
    """The master task ran past its budget (the task watchdog): raised by the compiled
    code at a loop or a section, caught by the executor, which cuts the task there."""

    def __init__(self, module: str, line: int) -> None:
        super().__init__(f"{module} line {line}")
        self.module = module
        self.line = line
