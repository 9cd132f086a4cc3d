"""Shared helpers of the PL7 tests: a compact dump of a tree, running snippets."""

from __future__ import annotations

import dataclasses
import enum
from pathlib import Path

from fieldtwin.pl7 import Executor, InMemory, parse
from fieldtwin.pl7 import tree as t
from fieldtwin.tsx.addressing import ObjectRef

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GOLDEN = Path(__file__).resolve().parent / "golden"


def dump(node: object) -> str:
    """``Assign(Const(0,D),[Table(B1,8)])``: every compared field, positions left out."""
    if isinstance(node, ObjectRef):
        return str(node)
    if isinstance(node, enum.Enum):
        return node.name
    if isinstance(node, tuple):
        return "[" + ",".join(dump(x) for x in node) + "]"
    if isinstance(node, t.Internal):
        return f"{node.kind}{node.index}"
    if dataclasses.is_dataclass(node) and not isinstance(node, type):
        parts = [dump(getattr(node, f.name)) for f in dataclasses.fields(node) if f.compare]
        return f"{type(node).__name__}({','.join(parts)})"
    return repr(node)


def dump_program(program: t.Program) -> str:
    """One line per sentence, comment or chart item."""
    lines: list[str] = []
    for section in program.sections:
        if isinstance(section, t.Literal):
            lines.append(f"%{section.name}")
            lines.extend(dump(s) for s in section.sentences)
        else:
            lines.append("%CHART")
            lines.extend(dump(i) for i in section.items)
    return "\n".join(lines) + "\n"


def run(text: str, cycles: int = 1, memory: InMemory | None = None) -> tuple[Executor, InMemory]:
    """Load ``text`` (a Literal-only program or sections) and run ``cycles`` master tasks."""
    memory = memory or InMemory()
    executor = Executor(parse(text), memory)
    for _ in range(cycles):
        executor.run_master_task()
    return executor, memory


def load(text: str) -> tuple[Executor, InMemory]:
    """Load ``text`` (a cold restart: internal bits and words cleared); run nothing."""
    memory = InMemory()
    return Executor(parse(text), memory), memory
