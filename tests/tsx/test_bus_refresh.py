"""The event-driven bus refresh gives the images the full refresh gives (DESIGN rule 3).

Two PLCs, one refreshing every slot at every master task (``event_driven=False``, what
the real PLC does), one reading a slot again only after its module's bus face
changed: the same random module activity (input words and bits, faults of every
category, outputs written, modules pulled out and put back, power breaks, cold
restarts, changes at the very instant of a refresh), with and without a program,
on a TSX 87 and on a TSX 47-20 (register words every second task).  After every
millisecond both show the same images, outputs, cycles and program state.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.tsx.module import IntelligentModule
from fieldtwin.tsx.plc import Plc
from tests.tsx.double import CONVERTER, DOUBLE, SENSOR, TERMINAL_BLOCK, Change, Command

SLOTS = (1, 2, 3)
PROGRAM = """%PRE
!IW1,1->W0;IW2,2->W1;IW3,3->W2
!IF I1,0.NOT I2,S THEN SET O1,1 ELSE RESET O1,1
!IF I3,S+IW3,0,4 THEN 5->OW3,2 ELSE 0->OW3,2
!I2,1->O2,0
!EOP
"""
FAULT_BITS = (3, TERMINAL_BLOCK, CONVERTER, SENSOR)  # blocking, module x2, application


changes = st.builds(
    Change,
    at_us=st.one_of(st.integers(0, 400_000), st.integers(0, 40).map(lambda k: k * 10_000)),
    slot=st.sampled_from(SLOTS),
    what=st.sampled_from(["iw", "bits", "fault", "read_faults"]),
    index=st.integers(0, 7),
    value=st.integers(0, 0xFFFF),
)
commands = st.builds(
    Command,
    what=st.sampled_from(["ow", "o", "remove", "reinsert", "break", "cold", "wait"]),
    slot=st.sampled_from(SLOTS),
    index=st.integers(0, 7),
    value=st.integers(0, 0xFFFF),
)


def build(model: str, event_driven: bool, program: bool) -> Plc:
    plc = Plc(model=model, scan_ms=10, event_driven=event_driven)
    for slot in SLOTS:
        plc.insert(DOUBLE, rack=0, slot=slot)
    if program:
        plc.load_program(PROGRAM)
    plc.advance(2.5)  # past the self-tests
    return plc


def apply_change(plc: Plc, change: Change) -> None:
    module = plc.module(0, change.slot)
    if change.what == "iw":
        module.iw[change.index] = change.value
    elif change.what == "bits":
        module.i_bits = change.value
    elif change.what == "fault":
        bit = FAULT_BITS[change.index % len(FAULT_BITS)]
        module.set_fault(bit, bool(change.value & 1))
    else:
        module.read_fault_string()


def schedule(plc: Plc, batch: list[Change]) -> None:
    base = plc.clock.now
    for change in batch:
        plc.clock.schedule(base + change.at_us, lambda now, c=change: apply_change(plc, c))


def command(plc: Plc, cmd: Command) -> None:
    if cmd.what == "ow":
        plc.write(f"OW{cmd.slot},{cmd.index}", cmd.value)
    elif cmd.what == "o":
        plc.write(f"O{cmd.slot},{cmd.index % 4}", cmd.value & 1)
    elif cmd.what == "remove":
        plc.remove(0, cmd.slot)
    elif cmd.what == "reinsert":
        plc.reinsert(0, cmd.slot)
    elif cmd.what == "break":
        plc.power_break(0.005 if cmd.value & 1 else 0.3)
    elif cmd.what == "cold":
        plc.cold_restart()


def face(plc: Plc) -> tuple[object, ...]:
    seen: list[object] = [plc.cycles, plc.now]
    for slot in SLOTS:
        module: IntelligentModule = plc.module(0, slot)
        seen += [plc.image(0, slot), plc.output_words(0, slot), plc.read(f"O{slot},1")]
        seen += [module.bus_read(), list(module.ow), module.o_bits, module.state]
    seen += [plc.data[:3], plc.bits[:1]]
    return tuple(seen)


def run_both(model: str, program: bool, steps: list[tuple[list[Change], Command]]) -> int:
    full, event = build(model, False, program), build(model, True, program)
    assert face(full) == face(event)
    compared = 0
    for batch, cmd in steps:
        for plc in (full, event):
            schedule(plc, batch)
            command(plc, cmd)
        assert face(full) == face(event)
        for _ in range(45):  # 45 ms: past every change of the batch, 1 ms at a time
            full.advance(0.001)
            event.advance(0.001)
            assert face(full) == face(event)
            compared += 1
        for plc in (full, event):
            plc.advance(0.4)
        assert face(full) == face(event)
    return compared


steps = st.lists(st.tuples(st.lists(changes, max_size=6), commands), min_size=1, max_size=6)


@settings(max_examples=40)
@given(steps=steps, program=st.booleans())
def test_event_driven_images_equal_a_full_refresh_on_a_tsx_87(
    steps: list[tuple[list[Change], Command]], program: bool
) -> None:
    assert run_both("TSX 87", program, steps) > 0


@settings(max_examples=40)
@given(steps=steps, program=st.booleans())
def test_event_driven_images_equal_a_full_refresh_on_a_tsx_47_20(
    steps: list[tuple[list[Change], Command]], program: bool
) -> None:
    # registers every second task (AEM 2.4-3): a word changed on an odd task waits
    assert run_both("TSX 47-20", program, steps) > 0


def test_an_idle_module_is_not_read_again() -> None:
    plc = build("TSX 87", True, False)
    module = plc.module(0, 1)
    reads = 0
    original = module.bus_read

    def counting() -> object:
        nonlocal reads
        reads += 1
        return original()

    module.bus_read = counting  # type: ignore[method-assign]
    image = plc.image(0, 1)
    plc.advance(1.0)  # 100 master tasks, nothing changes
    assert plc.image(0, 1) is image and not module.bus_dirty
    module.iw[4] = 0x1234
    assert module.bus_dirty
    plc.advance(0.01)
    assert plc.read("IW1,4") == 0x1234 and not module.bus_dirty
    assert reads == 0  # the refresh compares the face, it never builds a second image


def test_a_change_waits_for_the_end_of_the_master_task() -> None:
    # the image is the modules' state at the end of the previous master task
    plc = build("TSX 87", True, False)
    start = plc.now
    next_task = (start // 10_000 + 1) * 10_000
    plc.clock.schedule(next_task - 1, lambda now: plc.module(0, 2).iw.__setitem__(5, 77))
    plc.advance((next_task - 1 - start) / 1e6)
    assert plc.read("IW2,5") == 0
    plc.advance(1e-6)
    assert plc.read("IW2,5") == 77
