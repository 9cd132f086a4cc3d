"""A master task that changed nothing is skipped while nothing changes: same results.

Two executors of the same manual program on two in-memory memories, one skipping
its fixed points (the default), one running every task (``skip_idle = False``);
the same random activity of the modules and Text Blocks, sparse enough that the
programs sit idle between changes, the minute bit SY7 turning; after every task
both memories, charts, faults and started exchanges are equal.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.pl7 import Executor, InMemory, parse

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PROGRAMS = ["aem811_tank.pl7", "dem24_assembly.pl7", "scm_exchange.pl7"]

# (task, what, which, value): what 0 = an input bit, 1 = an input word, 2 = the fault
# bit, 3 = end the oldest exchange in progress (V = H'FE', H'77', 0 or any), 4 = a jump of
# time (the minute bit), 5 = an internal word written from outside (the console)
events = st.lists(
    st.tuples(st.integers(0, 299), st.integers(0, 5), st.integers(0, 63), st.integers(0, 0xFFFF)),
    max_size=40,
)


def build(name: str, skip: bool) -> tuple[Executor, InMemory]:
    memory = InMemory()
    executor = Executor(parse((EXAMPLES / name).read_text()), memory)
    executor.skip_idle = skip
    return executor, memory


def state(executor: Executor, memory: InMemory) -> tuple[object, ...]:
    modules = sorted(
        (key, m.iw[:], m.ow[:], m.i[:], m.o[:], m.fault[:]) for key, m in memory.modules.items()
    )
    started = [(s.index, s.command, s.m, s.c, s.length) for s in memory.started]
    return (
        memory.b[:],
        memory.w[:],
        memory.sy[:],
        memory.sw[:],
        modules,
        sorted((k, sorted(v.items())) for k, v in memory.txt.items()),
        started,
        sorted(memory.busy),
        executor.active_steps(),
        [str(f) for f in executor.faults],
        executor.cycles,
    )


def apply(memory: InMemory, what: int, which: int, value: int, answered: list[int]) -> None:
    slots = sorted(memory.modules)
    module = memory.modules[slots[which % len(slots)]]
    if what == 0:
        module.i[which % 16] = value & 1
    elif what == 1:
        module.iw[which % 8] = value
    elif what == 2:
        module.fault[0] = value & 1
    elif what == 3:
        waiting = [s.index for s in memory.started[answered[0] :] if s.index in memory.busy]
        if waiting:  # the reports the programs wait for, or any other
            memory.finish(waiting[0], v=(0xFE, 0x77, 0x00, value & 0xFF)[which % 4])
        answered[0] = len(memory.started)
    elif what == 5:
        memory.w[which] = value


@pytest.mark.parametrize("name", PROGRAMS)
@settings(max_examples=25)
@given(script=events)
def test_skipping_fixed_points_changes_nothing(
    name: str, script: list[tuple[int, int, int, int]]
) -> None:
    pair = [build(name, True), build(name, False)]
    marks = [[0], [0]]
    now = 0
    for task in range(300):
        for at, what, which, value in script:
            if at == task:
                if what == 4:
                    now += value * 1000
                for (_, memory), answered in zip(pair, marks, strict=True):
                    apply(memory, what, which, value, answered)
        now += 10_000
        for executor, _ in pair:
            executor.run_master_task(now)
        assert state(*pair[0]) == state(*pair[1])
    assert pair[1][0].skipped == 0


def test_an_idle_tank_program_is_skipped_until_an_input_changes() -> None:
    executor, memory = build("aem811_tank.pl7", True)
    aem = memory.module(0, 5)
    aem.iw[0], aem.iw[2] = 1 << 3, 1 << 0xD  # ready, in its default configuration
    memory.module(1, 4).i[0] = 1  # I14,0: Run
    for k in range(20):  # configuration and thresholds, each exchange answered
        executor.run_master_task(k * 10_000)
        aem.iw[2] &= ~(1 << 0xD)
        aem.iw[0] = (aem.iw[0] & ~(1 << 0xC)) | (aem.ow[0] & (1 << 0xC))
        for started in memory.started:
            if started.index in memory.busy:
                memory.finish(started.index, v=0xFE)
    assert memory.b[3] == 1  # measurement processing (SR2)
    skipped = executor.skipped
    for k in range(20, 70):  # the fault string read waits for its answer: idle
        executor.run_master_task(k * 10_000)
    assert executor.skipped - skipped >= 48
    aem.iw[3] = 1234  # a new measurement of tank 0
    executor.run_master_task(70 * 10_000)
    assert memory.w[0] == 1234  # it ran
    executor.run_master_task(71 * 10_000)
    assert memory.w[0] == 1234
    before = executor.skipped
    executor.run_master_task(72 * 10_000)
    assert executor.skipped == before + 1  # idle again
    aem.fault[0] = 1  # I5,S: SR3 reads the fault bit string
    for k in range(73, 80):
        executor.run_master_task(k * 10_000)
    assert memory.b[8] == 1 and 0 in memory.busy  # SR3: the fault string read waits
    before = executor.skipped
    executor.run_master_task(80 * 10_000)
    assert executor.skipped == before + 1  # waiting is idle
    memory.finish(0, v=0x77)  # its report comes (TXT0,D and TXT0,V, read by a reader)
    executor.run_master_task(81 * 10_000)
    assert memory.b[8] == 0  # SR3 L3 ran: RESET B8


def test_a_breakpoint_set_while_idle_is_still_reached() -> None:
    executor, _ = build("aem811_tank.pl7", True)
    for k in range(20):
        executor.run_master_task(k * 10_000)
    executor.break_at_label("PRE", 1)
    executor.run_master_task(20 * 10_000)
    assert executor.held is not None and executor.held.label == 1


def test_a_task_that_only_faults_is_not_a_fixed_point() -> None:
    # the exchange still in progress: every later EXCHG is a run-time fault, recorded
    # with its task; nothing else changes, yet no task may be skipped
    text = "%PRE\n!H'0500'->TXT0,M;H'0F'->TXT0,C;EXCHG TXT0\n!EOP\n"
    runs = []
    for skip in (True, False):
        memory = InMemory()
        executor = Executor(parse(text), memory)
        executor.skip_idle = skip
        for k in range(10):
            executor.run_master_task(k * 10_000)
        runs.append([str(f) for f in executor.faults])
    assert runs[0] == runs[1] and len(runs[0]) == 9
