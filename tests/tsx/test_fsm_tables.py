"""Generated tests of the TSX core's state-machine tables (tests/fsm_check.py):
every (state, input) pair on a real owner forced into the state."""

from __future__ import annotations

from fieldtwin.fsm import tables
from fieldtwin.tsx.bus import ModuleEvent, ModuleState
from fieldtwin.tsx.module import MODES
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.textblock import Answer
from fieldtwin.tsx.txt import TXT, TextBlock, TxtInput, TxtState
from tests.fsm_check import Forced, check_every_pair
from tests.tsx.double import DOUBLE


def _forced_module(state: ModuleState) -> Forced[ModuleState, ModuleEvent]:
    plc = Plc(scan_ms=10)
    mod = plc.insert(DOUBLE, rack=0, slot=5)  # a real module, in its self-test
    plc.start_exchange(m=0x0563, c=0x0F, recv_bytes=27)
    plc.advance(0.011)  # a version request held by the self-test
    mod._mode.state = state
    return Forced(lambda event: mod._fire(event, plc.now), lambda: mod.state)


def test_module_modes_every_pair() -> None:
    check_every_pair(MODES, _forced_module)


def _forced_text_block(state: TxtState) -> Forced[TxtState, TxtInput]:
    tb = TextBlock(0)
    tb.machine.state = state
    args = {TxtInput.REFUSE: (Answer.fault(5), 0), TxtInput.ANSWER: (Answer(0x3F), 0)}

    def fire(event: TxtInput) -> object:
        return tb.machine.fire(event, *args.get(event, ()))

    return Forced(fire, lambda: tb.state)


def test_text_block_every_pair() -> None:
    check_every_pair(TXT, _forced_text_block)


def test_the_tables_are_the_kernel_s() -> None:
    assert MODES in tables() and TXT in tables()
    tb = TextBlock(0)
    tb.machine.fire(TxtInput.START)
    tb.machine.fire(TxtInput.SUBMIT)
    tb.machine.fire(TxtInput.ANSWER, Answer(0x3F, b"V1"), 7)  # the action keeps the answer
    assert (tb.state, tb.answer, tb.answered_at_us) == (TxtState.ANSWERED, Answer(0x3F, b"V1"), 7)
