"""A parked master task is seen exactly as one that runs at every task instant.

Two PLCs side by side, one parking its idle master task (the default), one with an
event at every task (``Plc(park=False)``, the reference): the same program (none,
one reading module objects, one reading SY7, one reading the calendar words, one
counting every task, one whose chart waits on an input), the same random module
activity as clock events (on task instants, between them, at the very instant of a
task), the same commands between two runs (writes, Text Block exchanges,
breakpoint holds, STOP/RUN, restarts, power breaks, the calendar set, modules pulled
out and put back, changes and events scheduled from outside a run), and runs of
random lengths (whole tasks, single microseconds, long stretches).  After every run
both show the same task counts (the PLC's, the executor's, the skipped ones), the
same memory (W, B, SY, SW), images, outputs, Text Block results, and the modules saw
the same outputs at the same instants.
"""

from __future__ import annotations

from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.pl7.executor import Hit
from fieldtwin.tsx.plc import Plc
from tests.tsx.double import DOUBLE, SENSOR, Change, Command

SLOTS = (1, 2)
PROGRAMS: dict[str, str] = {
    "none": "",
    "objects": """%PRE
!IW1,1->W0;IW2,2->W1
!IF I1,0.NOT I2,S THEN SET O1,1 ELSE RESET O1,1
!IF I2,3 THEN 5->OW2,2 ELSE 0->OW2,2
!IF RE(I1,2) THEN W2+1->W2
!EOP
""",
    "minute": """%PRE
!IF SY7 THEN SET O1,0 ELSE RESET O1,0
!IF RE(SY7) THEN W3+1->W3
!EOP
""",
    "calendar": """%PRE
!SW51->W4;SW52->W5
!IF [SW51>30] THEN SET O2,0 ELSE RESET O2,0
!EOP
""",
    "counter": """%PRE
!W6+1->W6
!EOP
""",
    "chart": """%CHART
CHART INITIAL 1
T: 1>2
!   I1,3
CHART S(A)2
!  W7+1->W7
T: 2>1
!   NOT I1,3
%POST
!IF X2 THEN SET O1,2 ELSE RESET O1,2
!EOP
""",
}


changes = st.builds(
    Change,
    at_us=st.one_of(
        st.integers(0, 300_000),
        st.integers(0, 30).map(lambda k: k * 10_000),  # on a task instant
    ),
    slot=st.sampled_from(SLOTS),
    what=st.sampled_from(["iw", "bits", "fault", "chain"]),
    index=st.integers(0, 7),
    value=st.integers(0, 0xFFFF),
)
COMMANDS = [
    "wait",
    "ow",
    "o",
    "w",
    "txt",
    "hold",
    "resume",
    "stop",
    "start",
    "cold",
    "hot",
    "break",
    "calendar",
    "remove",
    "reinsert",
    "outside",
    "face",
]
commands = st.builds(
    Command,
    what=st.sampled_from(COMMANDS),
    slot=st.sampled_from(SLOTS),
    index=st.integers(0, 7),
    value=st.integers(0, 0xFFFF),
)
runs = st.one_of(
    st.integers(1, 40).map(lambda k: k * 10_000),  # whole tasks
    st.integers(1, 25_000),  # short, mostly off the task instants
    st.integers(1, 90).map(lambda k: k * 1_000_000),  # long: past SY7 and the calendar
)


def build(program: str, park: bool) -> tuple[Plc, list[tuple[int, int, list[int], int]]]:
    plc = Plc(model="TSX 87", scan_ms=10, park=park)
    seen: list[tuple[int, int, list[int], int]] = []
    for slot in SLOTS:
        module = plc.insert(DOUBLE, rack=0, slot=slot)
        write = module.bus_write

        def logged(ow: Any, o_bits: int, now: int, s: int = slot, w: Any = write) -> None:
            seen.append((now, s, list(ow), o_bits))
            w(ow, o_bits, now)

        module.bus_write = logged  # type: ignore[method-assign]
    if PROGRAMS[program]:
        plc.load_program(PROGRAMS[program])
    plc.advance(2.5)  # past the self-tests
    return plc, seen


def apply_change(plc: Plc, change: Change) -> None:
    module = plc.module(0, change.slot)
    if change.what in ("chain", "relay"):  # events that schedule the next a task later
        # (as a DEM's filter confirmation does, 10 ms after its edge) and change nothing
        # the PLC sees: the face changes at the end of the chain, and its order against
        # the task of that instant is the one the task's own sequence number gives
        then = "relay" if change.what == "chain" else ("bits", "iw")[change.value >> 8 & 1]
        later = Change(0, change.slot, then, change.index, change.value ^ 0xFF)
        delay = 10_000 * (1 + change.value % 2)
        plc.clock.call_later(delay, lambda now: apply_change(plc, later))
    elif change.what == "iw":
        module.iw[change.index] = change.value
    elif change.what == "bits":
        module.i_bits = change.value
    else:
        module.set_fault(SENSOR, bool(change.value & 1))


def schedule(plc: Plc, batch: list[Change]) -> None:
    base = plc.clock.now
    for change in batch:
        plc.clock.schedule(base + change.at_us, lambda now, c=change: apply_change(plc, c))


def command(plc: Plc, cmd: Command) -> None:
    program = plc.program
    what = cmd.what
    if what == "ow":
        plc.write(f"OW{cmd.slot},{cmd.index}", cmd.value)
    elif what == "o":
        plc.write(f"O{cmd.slot},{cmd.index % 4}", cmd.value & 1)
    elif what == "w":
        plc.write(f"W{cmd.index % 8}", cmd.value)
    elif what == "txt":
        if not plc.text_block(cmd.index % 2).state.value.startswith(("started", "in", "ans")):
            plc.start_exchange(0x0100 * cmd.slot, 1, [cmd.value], txt=cmd.index % 2)
    elif what == "hold" and program is not None and program.held is None:
        program.held = Hit(program.cycles)
    elif what == "resume" and program is not None:
        program.resume()
    elif what == "stop":
        plc.stop()
    elif what == "start" and plc.fault is None:
        plc.start()
    elif what == "cold":
        plc.cold_restart()
    elif what == "hot":
        plc.hot_restart()
    elif what == "break":
        plc.power_break(0.005 if cmd.value & 1 else 0.3)
    elif what == "calendar":
        plc.set_calendar(2000 + cmd.index, 1 + cmd.value % 12, 1, second=cmd.value % 60)
    elif what == "remove":
        plc.remove(0, cmd.slot)
    elif what == "reinsert":
        plc.reinsert(0, cmd.slot)
    elif what == "outside":  # an event scheduled between two runs, on or off a task instant
        delay = cmd.value % 3 * 5_000 + (cmd.index % 2) * 10_000
        change = Change(0, cmd.slot, "iw", cmd.index, cmd.value)
        plc.clock.call_later(delay, lambda now: apply_change(plc, change))
    elif what == "face":  # a module's face changed by hand between two runs
        plc.module(0, cmd.slot).iw[cmd.index] = cmd.value


def face(plc: Plc, seen: list[Any]) -> tuple[object, ...]:
    program = plc.program
    state: list[object] = [plc.now, plc.cycles, plc.mode]
    if program is not None:
        state += [program.cycles, program.skipped, program.held, program.active_steps()]
    for slot in SLOTS:
        state += [plc.image(0, slot), plc.output_words(0, slot), plc.read(f"O{slot},1")]
    for txt in (0, 1):
        block = plc.text_block(txt)
        state += [block.state, block.result]
    state += [plc.data[:8], plc.bits[:8], plc.sy[:20], plc.sw[50:57], len(seen), seen[-3:]]
    return tuple(state)


def run_both(program: str, steps: list[tuple[list[Change], Command, int]]) -> None:
    (parked, seen_p), (every, seen_e) = build(program, True), build(program, False)
    assert face(parked, seen_p) == face(every, seen_e)
    for batch, cmd, run_us in steps:
        for plc in (parked, every):
            schedule(plc, batch)
            command(plc, cmd)
        assert face(parked, seen_p) == face(every, seen_e), cmd
        for plc in (parked, every):
            plc.advance(run_us / 1e6)
        assert face(parked, seen_p) == face(every, seen_e), (cmd, run_us)
        assert seen_p == seen_e
    assert parked.clock.fired <= every.clock.fired


steps = st.lists(st.tuples(st.lists(changes, max_size=4), commands, runs), min_size=1, max_size=12)


@settings(max_examples=60)
@given(program=st.sampled_from(sorted(PROGRAMS)), steps=steps)
def test_a_parked_master_task_is_seen_as_one_run_at_every_task(
    program: str, steps: list[tuple[list[Change], Command, int]]
) -> None:
    run_both(program, steps)


def test_an_idle_plc_parks_its_master_task() -> None:
    plc, _ = build("objects", True)
    every, _ = build("objects", False)
    fired, fired_every = plc.clock.fired, every.clock.fired
    plc.advance(60.0)
    every.advance(60.0)
    assert plc.cycles == every.cycles and plc.program is not None
    assert plc.program.skipped == every.program.skipped > 5_900  # type: ignore[union-attr]
    assert every.clock.fired - fired_every >= 6_000  # an event per task
    assert plc.clock.fired - fired <= 70  # one a second at most (nothing else scheduled)


def test_the_minute_bit_wakes_a_parked_task_on_its_instant() -> None:
    plc, _ = build("minute", True)
    every, _ = build("minute", False)
    for _ in range(6):
        plc.advance(17.0)
        every.advance(17.0)
        assert plc.read("SY7") == every.read("SY7")
        assert plc.data[3] == every.data[3] and plc.read("O1,0") == every.read("O1,0")
    assert plc.data[3] >= 1


def test_a_chain_of_events_meets_the_parked_task_in_the_unparked_order() -> None:
    # an event on a task instant, scheduled well before it, runs before that instant's
    # task; what it schedules a task later must run before that later task too (the
    # task's number is taken after it), and so on: the face changes at the end of the
    # chain reach the image at the same task, and the outputs leave at the same instant
    runs = []
    for park in (True, False):
        plc, seen = build("objects", park)
        plc.advance(1.0)  # parked by now (nothing changes)
        module = plc.module(0, 1)

        def third(now: int, m: Any = module) -> None:
            m.i_bits = m.i_bits ^ 1  # I1,0: O1,1 follows at the next task but one

        def second(now: int, p: Plc = plc) -> None:
            p.clock.call_later(10_000, third)

        def first(now: int, p: Plc = plc) -> None:
            p.clock.call_later(10_000, second)

        plc.clock.call_later(50_000, first)
        plc.advance(0.2)
        runs.append((seen[-4:], plc.program.skipped if plc.program else None, plc.cycles))
    assert runs[0] == runs[1]
