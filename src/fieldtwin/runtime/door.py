"""The one command door: every action from outside the plant is a value, run by one dispatcher.

A control-API call (``set_input``, ``step``...) and a console line are each a
:class:`Command` - a kind, a name, its arguments - never a function.  The control
API submits the value to the runner's inbox (fieldtwin.runtime.inbox), which
hands it to the plant's :class:`Door` on the simulation's thread; a console on
the simulation's own thread (``fieldtwin console``, a Python session) gives its
lines to the same door; a replay re-submits the recorded values there.

The door runs a command with the handler its kind is served by (``serve``) and
tells its observers (``watch``) before and after each one: that is how a
recording sees the commands (fieldtwin.runtime.record) - nothing wraps the
control object's methods.  A command run inside another (a console line that
sets an input, a mode's own run) is the outer command's own business: observers
see only the outermost one, whose inputs a replay delivers again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from fieldtwin.errors import ConfigError

CALL = "call"  # a control-API command: name = the command, args = its arguments
LINE = "line"  # a console line: name = the line (and its text after a newline)
KINDS = (CALL, LINE)


@dataclass(frozen=True, slots=True)
class Command:
    """One action from outside, as a value (what a recording writes, a replay re-submits)."""

    kind: str
    name: str
    args: tuple[object, ...] = ()

    @classmethod
    def call(cls, name: str, *args: object) -> Command:
        return cls(CALL, name, args)

    @classmethod
    def line(cls, text: str) -> Command:
        return cls(LINE, text)


Handler = Callable[[Command], object]


class DoorObserver(Protocol):
    """Sees every outermost command: ``before`` it runs, ``after`` it returned or raised."""

    def before(self, command: Command) -> None: ...

    def after(self, command: Command, answer: object, error: BaseException | None) -> None: ...


class Door:
    """Runs commands, one at a time, on the simulation's thread (see the module docstring)."""

    def __init__(self) -> None:
        self._handlers: dict[str, list[Handler]] = {}
        self._observers: list[DoorObserver] = []
        self._depth = 0  # commands running (nested: a command that runs another)
        self.executed = 0  # outermost commands run so far

    def serve(self, kind: str, handler: Handler) -> Callable[[], None]:
        """Commands of ``kind`` run with ``handler`` (the last served wins); the function
        returned withdraws it (the one before serves again)."""
        if kind not in KINDS:
            raise ValueError(f"unknown command kind {kind!r} (allowed: {', '.join(KINDS)})")
        stack = self._handlers.setdefault(kind, [])
        stack.append(handler)

        def withdraw() -> None:
            if handler in stack:
                stack.remove(handler)

        return withdraw

    def watch(self, observer: DoorObserver) -> Callable[[], None]:
        """``observer`` sees every outermost command from now; the function returned stops it."""
        self._observers.append(observer)

        def stop() -> None:
            if observer in self._observers:
                self._observers.remove(observer)

        return stop

    @property
    def running(self) -> bool:
        """A command is running (one it runs is its own business)."""
        return self._depth > 0

    def handler(self, kind: str) -> Handler:
        stack = self._handlers.get(kind)
        if not stack:
            raise ConfigError(f"nothing here runs {kind} commands (no {kind} handler served)")
        return stack[-1]

    def dispatch(self, command: Command, handler: Handler | None = None) -> object:
        """Run ``command`` (with ``handler``, else its kind's); its answer.  The observers
        see it before and after, unless it runs inside another command."""
        run = handler if handler is not None else self.handler(command.kind)
        if self._depth:
            self._depth += 1
            try:
                return run(command)
            finally:
                self._depth -= 1
        observers = tuple(self._observers)
        for observer in observers:
            observer.before(command)
        self._depth = 1
        try:
            answer = run(command)
        except BaseException as exc:
            self._depth = 0
            for observer in observers:
                observer.after(command, None, exc)
            raise
        self._depth = 0
        self.executed += 1
        for observer in observers:
            observer.after(command, answer, None)
        return answer


__all__ = ["CALL", "KINDS", "LINE", "Command", "Door", "DoorObserver", "Handler"]
