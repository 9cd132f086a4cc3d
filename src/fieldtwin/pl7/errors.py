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

    def __init__(
        self,
        line: int,
        column: int,
        token: str,
        expected: str,
        source: str = "",
        *,
        said: str | None = None,
    ) -> None:
        """``said`` replaces ``expected X`` in the message (``unknown instruction (did
        you mean CALL?)``)."""
        self.line = line
        self.column = column
        self.token = token
        self.expected = expected
        self.source = source
        self.said = said
        where = f"{source}: " if source else ""
        shown = "end of file" if token == "" else repr(token)
        what = said if said is not None else f"expected {expected}"
        super().__init__(f"{where}line {line}, column {column}: {shown}: {what}")


class ObjectRefused(ConfigError):
    """An object the PLC refused while a sentence was compiled (a module slot that is
    empty, say): its line and text; the loader adds the column (Executor.from_source)."""

    def __init__(self, line: int, token: str, reason: str) -> None:
        self.line, self.token, self.reason = line, token, reason
        super().__init__(f"line {line}: {token!r}: {reason}")


class ProgramFault(FieldtwinError):
    """A run-time error of the program (caught by the executor, never raised out of it)."""


class WatchdogOverrun(FieldtwinError):
    """The master task ran past its budget (the task watchdog): raised by the compiled
    code at a loop or a section, caught by the executor, which cuts the task there."""

    def __init__(self, module: str, line: int) -> None:
        super().__init__(f"{module} line {line}")
        self.module = module
        self.line = line
