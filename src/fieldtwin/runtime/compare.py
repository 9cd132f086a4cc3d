"""Comparing two streams of output records: the first difference, shown in context.

A replay's outputs against the recording's (fieldtwin.replay), or two recordings'
(``fieldtwin diff``); both streams are read one record at a time, and only the
context of the first difference is kept.
"""

from __future__ import annotations

import json
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.recfile import Record

CONTEXT = 3  # records shown before and after a first difference


@dataclass(frozen=True, slots=True)
class Difference:
    """Where two streams of outputs part, and the text that shows it."""

    index: int
    text: str


def show(record: Record | None) -> str:
    """One record as a line: ``t = 1.234567 s  send t3  00 01 00 00 00 06``."""
    if record is None:
        return "(nothing: the stream has ended)"
    kind, t_us, rest = record[0], record[1], record[2:]
    if kind == "send":
        return f"t = {t_us / 1e6:.6f} s  send {rest[0]}  {_spaced(rest[1])}"
    if kind == "chars":
        text = bytes.fromhex(rest[3]).decode("latin-1")
        return f"t = {t_us / 1e6:.6f} s  chars {rest[0]} channel {rest[1]} {rest[2]}  {text!r}"
    if kind in ("object", "led"):
        return f"t = {t_us / 1e6:.6f} s  {kind} {rest[0]} {rest[1]} = {rest[2]}"
    if kind == "dem":
        body = " ".join(str(r) for r in rest[3:-1])
        lost = "" if rest[-1] else " (lost: stack full)"
        return f"t = {t_us / 1e6:.6f} s  dem {rest[0]} {rest[2]} {body} at {rest[1]}{lost}"
    if kind == "result":
        return f"t = {t_us / 1e6:.6f} s  result of {rest[0]}: {json.dumps(rest[1])[:200]}"
    at = f"t = {t_us / 1e6:.6f} s"
    if kind in INPUT_FORMS and len(rest) >= 1:
        fired, fields = rest[0], rest[1:]
        return f"{at}  {INPUT_FORMS[kind](fields)}  (after {fired} clock events)"
    return f"{at}  {kind} " + " ".join(str(r) for r in rest)


def _call(fields: Sequence[object]) -> str:
    args = fields[1] if len(fields) > 1 and isinstance(fields[1], list) else []
    return f"control {fields[0]}({', '.join(json.dumps(a) for a in args)})"


INPUT_FORMS: dict[str, Callable[[Sequence[object]], str]] = {
    "data": lambda f: f"data {f[0]}  {_spaced(str(f[1]))}",
    "accept": lambda f: f"accept on {f[0]}",
    "close": lambda f: f"close {f[0]}",
    "bind": lambda f: f"bind {' '.join(str(g) for g in f[0])}",  # type: ignore[attr-defined]
    "line": lambda f: f"console {str(f[0])!r}",
    "call": _call,
    "ret": lambda f: "(the command returned)",
    "settings": lambda f: (
        f"settings {f[0]}  master {f[1] or '(unnamed rate)'} Bd, {f[2]} stop bit(s)"
        + (", odd parity" if f[3] else "")
    ),
}


def _spaced(hex_text: str, limit: int = 64) -> str:
    data = bytes.fromhex(hex_text)
    text = data[:limit].hex(" ")
    return text + (f" ... ({len(data)} bytes)" if len(data) > limit else "")


def compare(
    expected: Sequence[Record],
    actual: Sequence[Record],
    *,
    names: tuple[str, str] = ("recorded", "replayed"),
) -> Difference | None:
    """The first difference of two output streams (same record, same instant), or None."""
    comparer = Comparer(iter(expected), names=names)
    for record in actual:
        comparer.append(record)
    return comparer.finish()


def _refusal(record: Record | None) -> str | None:
    """A command's refusal as what went wrong, without what it says is allowed: the text
    of ``{"error": "unknown command 'no' (allowed: read, write, ...)"}`` up to its " ("."""
    if record is None or len(record) != 4 or record[0] != "result":
        return None
    result = record[3]
    if not isinstance(result, dict) or set(result) != {"error"}:
        return None
    error = result["error"]
    return error.split(" (", 1)[0] if isinstance(error, str) else None


def _same_refusal(wanted: Record | None, record: Record) -> bool:
    """The same command refused for the same reason at the same instant, the list of what
    is allowed aside: a newer release knows more commands and arguments, which the
    recorded plant did not do differently (docs/record.md, "What identical means")."""
    if wanted is None or wanted[:3] != record[:3]:
        return False
    left = _refusal(wanted)
    return left is not None and left == _refusal(record)


class Comparer:
    """Compares records as a replay produces them with the expected ones, one by one:
    only the context of the first difference is kept (bounded memory)."""

    def __init__(
        self,
        expected: Iterator[Record],
        *,
        names: tuple[str, str] = ("recorded", "replayed"),
        on_error: Callable[[ConfigError], None] | None = None,
    ) -> None:
        self._expected = expected
        self._on_error = on_error  # a damaged expected stream: told there, then it ends
        self.names = names
        self.expected = 0  # expected records seen (all of them once finished)
        self.produced = 0
        self._before: deque[Record] = deque(maxlen=CONTEXT)
        self.index: int | None = None
        self._left: Record | None = None
        self._right: Record | None = None
        self._after_right: list[Record] = []

    def _next(self) -> Record | None:
        try:
            record = next(self._expected, None)
        except ConfigError as exc:
            if self._on_error is None:
                raise
            self._on_error(exc)
            self._expected = iter(())
            return None
        if record is not None:
            self.expected += 1
        return record

    def append(self, record: Record) -> None:
        self.produced += 1
        if self.index is None:
            wanted = self._next()
            if wanted == record or _same_refusal(wanted, record):
                self._before.append(record)
                return
            self.index, self._left, self._right = self.produced - 1, wanted, record
        elif len(self._after_right) < CONTEXT:
            self._after_right.append(record)

    def finish(self) -> Difference | None:
        """Once the replay has ended: the first difference, or None."""
        if self.index is None:
            wanted = self._next()
            if wanted is None:
                return None
            self.index, self._left, self._right = self.produced, wanted, None
        after_left: list[Record] = []
        while len(after_left) < CONTEXT and (record := self._next()) is not None:
            after_left.append(record)
        while self._next() is not None:  # how many there were, for the text
            pass
        names, index = self.names, self.index
        lines = [f"first difference at output {index + 1} (of {self.expected} {names[0]}):"]
        lines.extend(f"    same      {show(r)}" for r in self._before)
        width = max(len(n) for n in names)
        lines.append(f"  - {names[0]:<{width}} {show(self._left)}")
        lines.append(f"  + {names[1]:<{width}} {show(self._right)}")
        for name, after in zip(names, (after_left, self._after_right), strict=True):
            if after:
                lines.append(f"    then, {name}:")
                lines.extend(f"        {show(r)}" for r in after)
        return Difference(index, "\n".join(lines))


__all__ = ["CONTEXT", "Comparer", "Difference", "compare", "show"]
