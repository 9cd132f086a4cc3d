"""Issue 13/15: after a sample that leaves the sampled channel's low, high and
hysteresis states as they were, a TES 8EA only sets its alarm latches again and
keeps its reflex outputs (``AnalogInputs._judge_sampled``); every register and
output reads what a full evaluation after every sample gave.

Two TES 8EA live the same random history: sine, square and constant inputs, level
changes, time, master writes of thresholds, threshold outputs, polarity and of the
status word (resetting the latched alarm bits), power cycles.  The reference has the
shortcuts off (``_on_latch`` None: every sample evaluates the reflex outputs;
``direct_wake`` False: every sample schedules the next through ``_wake``).
"""

from __future__ import annotations

from hypothesis import example, given, settings
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
    # status writes: the master resets the latched alarm bits
    st.tuples(st.just("write"), st.tuples(st.just(0x000), st.sampled_from([0, 0x40, 0x80]))),
    st.tuples(st.just("level"), st.tuples(st.integers(0, 7), st.sampled_from([0.0, 5.0, 9.5]))),
    st.tuples(st.just("power"), st.just(0)),
)


def _tes(shortcut: bool) -> Tes:
    tes = Tes("TES 8EA")
    for k in range(8):
        if k % 3 == 1:
            tes.set_signal(f"a{k}", Sine(5.0, 4.5, 300_000 * (k + 1)))
        elif k % 3 == 2:
            tes.set_signal(f"a{k}", Square(1.0, 9.0, 200_000 * (k + 1)))
        else:
            tes.set_input(k, 3.0 + k / 2)
    # channel 0 (constant) over its high threshold, channel 3 (constant) under its low;
    # channel 2 (square) and 4 (sine) crossing theirs, driving reflex outputs 0, 1, 2
    setup = [(0x02B, 100), (0x023 + 3, 1000), (0x023 + 2, 300), (0x02B + 2, 700)]
    setup += [(0x023 + 4, 400), (0x02B + 4, 600), (0x033 + 2, 0x0100), (0x033 + 4, 0x0202)]
    for address, value in setup:
        tes.execute(WriteWord(address, value), Link.RS485, 0, False)
    if not shortcut:
        tes.ai._on_latch = None
        tes.ai.direct_wake = False
    return tes


def _map(tes: Tes) -> list[int]:
    return [tes.registers.peek(r, tes.clock.now) for r in tes.registers.table.values()]


def _next(tes: Tes) -> list[int | None]:
    """When each channel samples next (None: settled)."""
    handles = [ch.handle for ch in tes.ai.channels.values()]
    return [h.time if h is not None and h.active else None for h in handles]


def _outputs(tes: Tes) -> list[bool]:
    return [tes.digital_output(o) for o in range(4)]


@settings(max_examples=80, deadline=None)
@given(st.lists(_step, min_size=1, max_size=25))
@example([("advance", 300_000), ("write", (0x000, 0)), ("advance", 300_000)])
def test_the_reflex_shortcut_changes_nothing(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    fast, ref = _tes(True), _tes(False)
    for step in steps:
        for tes in (fast, ref):
            kind, arg = step
            if kind == "advance":
                tes.clock.advance(arg)
            elif kind == "write":
                address, value = arg
                tes.execute(WriteWord(address, value), Link.RS485, tes.clock.now, False)
            elif kind == "level":
                tes.set_input(arg[0], arg[1])
            else:
                tes.power_cycle()
        assert _map(fast) == _map(ref), step
        assert _outputs(fast) == _outputs(ref), step
        assert fast.do.reflex == ref.do.reflex, step
        assert fast.ram.status == ref.ram.status, step  # the latches themselves
        assert fast.clock.fired == ref.clock.fired, step  # the same samples, same instants
        assert _next(fast) == _next(ref), step


def test_the_shortcut_is_taken() -> None:
    """A sine that stays over its channel's high threshold samples on, evaluating the
    reflex outputs only at its first sample; the latch is set again after a reset."""
    tes = Tes("TES 8EA")
    write = WriteWord(0x02B + 1, 200)  # channel 1's high threshold, under the sine
    tes.execute(write, Link.RS485, tes.clock.now, False)
    tes.set_signal("a1", Sine(5.0, 0.5, 1_000_000))
    calls: list[int] = []
    original = tes.ai._on_evaluate

    def counted(now: int) -> None:
        calls.append(now)
        original(now)

    tes.ai._on_evaluate = counted
    tes.clock.advance(2_000_000)
    # the first sample of each of the 8 channels; channel 1's 31 later ones keep them
    assert len(calls) == 8
    assert tes.ram.status & 0x80
    tes.execute(WriteWord(0x000, 0), Link.RS485, tes.clock.now, False)  # master reset
    assert tes.ram.status & 0x80 == 0
    tes.clock.advance(200_000)
    assert len(calls) == 8
    assert tes.ram.status & 0x80  # latched again by a shortcut sample
