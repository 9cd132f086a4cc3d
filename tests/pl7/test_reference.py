"""The compiled executor against the tree-walking reference (pl7/reference.py):
generated programs, the same stimuli, the same memory after every master task.

The compiled side keeps its shortcut (an idle task is skipped, pl7/watch.py); the
reference runs every task, so the property checks the shortcut too."""

from __future__ import annotations

import dataclasses
import random
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fieldtwin.pl7 import Executor, InMemory, format_program, parse
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.reference import Reference, bta
from fieldtwin.tsx.addressing import ObjectRef

from .helpers import EXAMPLES
from .test_properties import _checks
from .test_roundtrip import programs


def _rebuild(node: Any, change: Callable[[Any], Any]) -> Any:
    """``node`` rebuilt bottom-up with ``change`` applied to every tree node."""
    if isinstance(node, tuple):
        return tuple(_rebuild(x, change) for x in node)
    if isinstance(node, t.Pos | ObjectRef) or not dataclasses.is_dataclass(node):
        return node
    fields = {f.name: _rebuild(getattr(node, f.name), change) for f in dataclasses.fields(node)}
    return change(type(node)(**fields))


def repaired(program: t.Program) -> t.Program:
    """Most generated programs jump to labels or call subroutines they lack, or have a
    chart the checker refuses: JUMPs and CALLs are pointed at what exists (or become
    RET), and a refused chart is dropped, its steps read as internal bits."""
    literals = [s for s in program.sections if isinstance(s, t.Literal)]
    calls = sorted(int(s.name[2:]) for s in literals if s.name.startswith("SR"))
    sections: list[t.Section] = []
    for section in program.sections:
        if isinstance(section, t.Literal):
            labels = sorted(
                x.label for x in section.sentences if isinstance(x, t.Sentence) and x.label
            )

            def point(node: Any, labels: list[int] = labels) -> Any:
                if isinstance(node, t.Jump) and node.label not in labels:
                    return t.Jump(labels[node.label % len(labels)]) if labels else t.Ret()
                if isinstance(node, t.Call) and node.sr not in calls:
                    return t.Call(calls[node.sr % len(calls)]) if calls else t.Ret()
                return node

            section = _rebuild(section, point)
        sections.append(section)
    fixed = t.Program(tuple(sections))
    if _checks(fixed):
        return fixed

    def no_steps(node: Any) -> Any:
        if isinstance(node, t.Internal) and node.kind in ("X", "XM"):
            return t.Internal("B", node.index)
        return node

    kept = tuple(s for s in fixed.sections if isinstance(s, t.Literal))
    return _rebuild(t.Program(kept), no_steps)  # type: ignore[no-any-return]


SLOTS = (2, 5, 14, 23)  # the module slots the generated programs use (test_roundtrip)


def state(memory: InMemory, engine: Executor | Reference, other: InMemory) -> dict[str, Any]:
    """Everything a program can change or a user can see, the lazily made parts
    (module images, Text Blocks) normalized against the ``other`` memory."""
    modules = {}
    for key in sorted(set(memory.modules) | set(other.modules)):
        image = memory.module(*key)
        modules[key] = (image.iw, image.ow, image.i, image.o, image.fault)
    for index in range(10):
        memory.text_block(index)
    return {
        "b": memory.b,
        "w": memory.w,
        "sy": memory.sy,
        "sw": memory.sw,
        "modules": modules,
        "txt": dict(sorted(memory.txt.items())),
        "busy": sorted(memory.busy),
        "started": memory.started,
        "cycles": engine.cycles,
        "faults": list(engine.faults),
        "overrun": engine.overrun,
        "steps": engine.active_steps(),
    }


# one stimulus between two master tasks: what the outside world changes
stimuli = st.fixed_dictionaries(
    {
        "w1": st.integers(0, 0xFFFF),
        "iw": st.tuples(st.sampled_from(SLOTS), st.integers(0, 7), st.integers(0, 0xFFFF)),
        "i": st.tuples(st.sampled_from(SLOTS), st.integers(0, 15), st.integers(0, 1)),
        "fault": st.integers(0, 1),
        "finish": st.one_of(st.none(), st.integers(0, 9)),
        "restart": st.sampled_from([None] * 8 + ["hot", "cold"]),
        "now_us": st.one_of(st.none(), st.integers(0, 10**9)),
    }
)


def apply(memory: InMemory, stimulus: dict[str, Any]) -> None:
    memory.w[1] = stimulus["w1"]
    slot, index, value = stimulus["iw"]
    memory.write(f"IW{slot},{index}", value)
    slot, index, bit = stimulus["i"]
    memory.write(f"I{slot},{index:X}", bit)
    memory.write("I5,S", stimulus["fault"])
    if stimulus["finish"] is not None and stimulus["finish"] in memory.busy:
        memory.finish(stimulus["finish"], v=stimulus["w1"])


def fill(memory: InMemory, seed: int) -> None:
    """The same random contents in both memories (else most objects read 0 and an
    AND of them hides what the program computes)."""
    rng = random.Random(seed)
    memory.b[:64] = [rng.randint(0, 1) for _ in range(64)]
    memory.sy[2:64] = [rng.randint(0, 1) for _ in range(62)]
    for table in (memory.w, memory.sw):
        table[:64] = [
            rng.choice((0, 1, 5, 0x7FFF, 0x8000, 0xFFFF, rng.randint(0, 0xFFFF))) for _ in range(64)
        ]
    for slot in SLOTS:
        for name, size in (("IW", 8), ("OW", 8)):
            for i in range(size):
                memory.write(f"{name}{slot},{i}", rng.randint(0, 0xFFFF))
        for i in range(16):
            memory.write(f"I{slot},{i:X}", rng.randint(0, 1))
            memory.write(f"O{slot},{i:X}", rng.randint(0, 1))
    for index in range(10):
        fields = memory.text_block(index)
        for name in ("M", "C", "L", "V", "R", "S"):
            fields[name] = rng.randint(0, 0xFFFF)
        fields["E"] = rng.randint(0, 1)


def compare(
    program: t.Program, script: list[dict[str, Any]], budget: int | None, seed: int | None = None
) -> tuple[Executor, Reference]:
    compiled_memory, reference_memory = InMemory(), InMemory()
    compiled = Executor(program, compiled_memory)
    reference = Reference(program, reference_memory)
    if seed is not None:
        fill(compiled_memory, seed)
        fill(reference_memory, seed)
    if budget is not None:
        compiled.budget = reference.budget = budget
    pair = (compiled_memory, reference_memory)
    assert state(*pair[:1], compiled, pair[1]) == state(pair[1], reference, pair[0])
    for task, stimulus in enumerate(script):
        for memory in (compiled_memory, reference_memory):
            apply(memory, stimulus)
        if stimulus["restart"] == "hot":
            compiled.hot_restart()
            reference.hot_restart()
        elif stimulus["restart"] == "cold":
            compiled.cold_restart()
            reference.cold_restart()
        ran = compiled.run_master_task(stimulus["now_us"])
        assert reference.run_master_task(stimulus["now_us"]) == ran
        a = state(compiled_memory, compiled, reference_memory)
        b = state(reference_memory, reference, compiled_memory)
        assert a == b, f"after master task {task + 1}:\n{format_program(program)}"
    return compiled, reference


@settings(
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
@given(
    programs().map(repaired),
    st.lists(stimuli, min_size=1, max_size=6),
    st.one_of(st.none(), st.integers(1, 60), st.integers(1, 2000)),
    st.integers(0, 2**32),
)
def test_compiled_and_evaluated_give_the_same_memory_after_every_task(
    program: t.Program, script: list[dict[str, Any]], budget: int | None, seed: int
) -> None:
    assume(_checks(program))
    # printed and parsed again: the sentences have lines (faults and overruns name them)
    compare(parse(format_program(program)), script, budget, seed)


@settings(max_examples=100, deadline=None)
@given(st.lists(stimuli, min_size=1, max_size=4))
def test_the_same_on_a_program_that_settles(script: list[dict[str, Any]]) -> None:
    # idle tasks: the compiled side skips them (a fixed point), the reference runs them
    text = """%PRE
!IF RE(I5,0) THEN INC W10
![IW5,0 > W11] -> B3
!IF B3 THEN IW5,0 -> W11
!IF B3 . NOT I5,1 THEN EXCHG TXT0
"""
    held = [s | {"restart": None} for s in script for _ in range(4)]  # each held 4 tasks
    compiled, _ = compare(parse(text), held, None)
    assert compiled.skipped > 0  # the shortcut was taken, and changed nothing


@pytest.mark.parametrize("name", ["aem811_tank.pl7", "dem24_assembly.pl7", "scm_exchange.pl7"])
def test_the_examples_give_the_same_memory(name: str) -> None:
    program = parse((EXAMPLES / name).read_text(), name)
    script = [
        {
            "w1": k * 37 % 65536,
            "iw": (SLOTS[k % 4], k % 8, (k * 7919) % 65536),
            "i": (SLOTS[k % 3], k % 16, k % 2),
            "fault": int(k % 11 == 0),
            "finish": k % 10,
            "restart": "hot" if k == 20 else None,
            "now_us": k * 7_000_000,
        }
        for k in range(40)
    ]
    compare(program, script, None)


def test_the_reference_writes_bta_as_the_manual_does() -> None:
    assert bta(123) == [
        ord("+") | ord("0") << 8,
        ord("0") | ord("1") << 8,
        ord("2") | ord("3") << 8,
    ]
    assert bta(0xFFFF) == [
        ord("-") | ord("0") << 8,
        ord("0") | ord("0") << 8,
        ord("0") | ord("1") << 8,
    ]


def test_a_watchdog_trip_is_where_the_compiled_code_has_it() -> None:
    text = "%PRE\n!L0 : INC W5\n!IF [W5 < 30000] THEN JUMP L0\n"
    quiet = {"w1": 0, "iw": (5, 0, 0), "i": (5, 0, 0), "fault": 0}
    quiet |= dict.fromkeys(("finish", "now_us", "restart"))
    compiled, reference = compare(parse(text), [quiet, quiet], 2000)
    assert compiled.overrun is not None and compiled.overrun.line == 2
    assert reference.overrun == compiled.overrun  # same section, line and task
