"""Issue 15: after a sample the TES 8EA judges only the sampled channel's thresholds;
every register reads what judging all channels at every sample gave.

Two TES 8EA live the same random history (sine and square inputs, time, master
writes of thresholds, threshold outputs and polarity); the reference judges every
channel after every sample (the earlier behaviour).
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.modbus.model import Link, WriteWord
from fieldtwin.signals import Sine, Square
from fieldtwin.tes import Tes

_write = st.one_of(
    st.tuples(st.integers(0x023, 0x032), st.integers(0, 1023)),  # low / high thresholds
    st.tuples(st.integers(0x033, 0x03A), st.sampled_from([0x0100, 0x0202, 0x03FF, 0xFF00])),
    st.tuples(st.just(0x03B), st.integers(0, 15)),  # polarity
)
_step = st.one_of(
    st.tuples(st.just("advance"), st.integers(1_000, 400_000)),
    st.tuples(st.just("write"), _write),
)


def _tes(reference: bool) -> Tes:
    tes = Tes("TES 8EA")
    for k in range(8):
        if k % 2:
            tes.set_signal(f"a{k}", Sine(5.0, 4.5, 300_000 * (k + 1)))
        else:
            tes.set_signal(f"a{k}", Square(1.0, 9.0, 200_000 * (k + 1)))
    if reference:
        ai = tes.ai
        ai._judge_sampled = lambda ch, now: ai.evaluate(now)  # type: ignore[method-assign]
    return tes


def _map(tes: Tes) -> list[int]:
    return [tes.registers.peek(r, tes.clock.now) for r in tes.registers.table.values()]


@settings(max_examples=40, deadline=None)
@given(st.lists(_step, min_size=1, max_size=20))
def test_judging_the_sampled_channel_only_changes_nothing(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    fast, ref = _tes(False), _tes(True)
    for step in steps:
        for tes in (fast, ref):
            if step[0] == "advance":
                tes.clock.advance(step[1])
            else:
                address, value = step[1]
                tes.execute(WriteWord(address, value), Link.RS485, tes.clock.now, False)
        assert _map(fast) == _map(ref), step
        assert [fast.digital_output(o) for o in range(4)] == [
            ref.digital_output(o) for o in range(4)
        ]
