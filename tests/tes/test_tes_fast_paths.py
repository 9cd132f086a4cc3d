"""Issue 15: the fast read/write paths of the TES answer exactly what word-by-word access does.

Two TES of the same model live the same random history (pulsing inputs, time,
master reads and writes of random spans).  One answers through ``execute`` (the
span cache, ``get_words`` computing a 32-bit pair once, ``put_words`` setting a
pair at once); the other through the reference: ``RegisterFile.get`` / ``put``
of each word in order.  Every answer and then the whole map must be equal.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.modbus.model import ExceptionCode, Link, ReadWords, Result, WriteWords
from fieldtwin.signals import PulseTrain
from fieldtwin.tes import Tes
from fieldtwin.tes.kinds import PAIRS

BAD_ADDRESS = ExceptionCode.ILLEGAL_DATA_ADDRESS
MODELS = ("TES 32EST", "TES 32ET", "TES 8EA", "TES 32ST", "TES 16EST")

_op = st.one_of(
    st.tuples(st.just("advance"), st.integers(1, 3_000_000)),
    st.tuples(st.just("read"), st.integers(0, 0x1C0), st.integers(1, 125)),
    st.tuples(
        st.just("write"),
        st.integers(0, 0x1C0),
        st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=20),
    ),
)


def _reference_read(tes: Tes, address: int, count: int) -> Result:
    table = tes.registers.table
    regs = [table.get(a) for a in range(address, address + count)]
    tes.slave_adapter.begin_exchange(Link.RS485, tes.clock.now)  # a refused one is a request too
    if any(r is None for r in regs) or count > 125:
        tes.slave_adapter.end_exchange()
        return BAD_ADDRESS
    out = tuple(tes.registers.get(r, tes.clock.now) for r in regs if r is not None)
    tes.slave_adapter.end_exchange()
    return out


def _reference_write(tes: Tes, address: int, values: list[int]) -> Result:
    table = tes.registers.table
    regs = [table.get(a) for a in range(address, address + len(values))]
    tes.slave_adapter.begin_exchange(Link.RS485, tes.clock.now)
    if any(r is None or not r.access.writable for r in regs):
        tes.slave_adapter.end_exchange()
        return BAD_ADDRESS
    for reg, value in zip(regs, values, strict=True):
        assert reg is not None
        tes.registers.put(reg, value, tes.clock.now)
    tes.slave_adapter.end_exchange()
    return None


def _whole_map(tes: Tes) -> list[int]:
    return [tes.registers.peek(r, tes.clock.now) for r in tes.registers.table.values()]


def _pulsing(model: str) -> Tes:
    tes = Tes(model)
    for i in range(min(tes.model.digital_inputs, 4)):
        tes.set_signal(i, PulseTrain(period_us=200_000 * (i + 1), duty=0.3))
    return tes


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(MODELS), st.lists(_op, max_size=25))
def test_fast_paths_answer_as_word_by_word(model: str, ops: list[tuple]) -> None:  # type: ignore[type-arg]
    fast, ref = _pulsing(model), _pulsing(model)
    for op in ops:
        now = fast.clock.now
        if op[0] == "advance":
            fast.clock.advance(op[1])
            ref.clock.advance(op[1])
            continue
        if op[0] == "read":
            got = fast.execute(ReadWords(3, op[1], op[2]), Link.RS485, now, False)
            want = _reference_read(ref, op[1], op[2])
        else:
            got = fast.execute(WriteWords(op[1], tuple(op[2])), Link.RS485, now, False)
            want = _reference_write(ref, op[1], op[2])
        assert got == want, op
        assert _whole_map(fast) == _whole_map(ref), op


def test_a_pair_written_whole_reads_back_what_was_written() -> None:
    tes = _pulsing("TES 32EST")
    tes.advance(1.7)
    table = tes.registers.table.values()
    pairs = [r.address for r in table if r.kind in PAIRS and r.index // 2 < 16]
    assert len(pairs) == 6 * 2 * 16  # six 32-bit values per fitted input, two words each
    for address in pairs[::2]:  # the high word first
        now = tes.clock.now
        assert tes.execute(WriteWords(address, (0x0001, 0x2345)), Link.RS485, now, False) is None
        got = tes.execute(ReadWords(3, address, 2), Link.RS485, tes.clock.now, False)
        assert got == (0x0001, 0x2345), hex(address)
