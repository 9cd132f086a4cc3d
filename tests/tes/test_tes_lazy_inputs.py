"""Issue 15: a TES digital input that follows a signal is computed at read time
(``DigitalInputs.follow``): no clock event per edge or confirmation, a pulse train's
whole periods jumped at once; every register reads what an event per edge gave.

Two TES live the same random history: pulse trains (any period, duty, phase, some
shorter than the filters), edge lists and random edges on random inputs, time (up to
minutes: the beat's catch-ups and the jumps), master reads of the whole map
(memorized inputs restored), master writes of the filter times and of the 32-bit
counters and chronometers, fixed levels, power cycles, and on a TES 32ET-S wiring
faults.  The reference has ``lazy`` off: an event per edge, as before.
"""

from __future__ import annotations

from hypothesis import example, given, settings
from hypothesis import strategies as st

from fieldtwin.clock import S
from fieldtwin.modbus.model import Link, ReadWords, WriteWord
from fieldtwin.signals import Edges, PulseTrain, RandomEdges
from fieldtwin.tes import Tes
from fieldtwin.tes.digital import Beat, DigitalInputs
from fieldtwin.tes.kinds import PAIRS

_pulse = st.builds(
    PulseTrain,
    period_us=st.integers(2_000, 3_000_000),
    duty=st.sampled_from([0.0, 0.02, 0.1, 0.5, 0.9, 0.99, 1.0]),
    start_us=st.integers(0, 2_000_000),
    high_first=st.booleans(),
)
_edges = st.builds(
    Edges,
    initial=st.booleans(),
    times_us=st.lists(st.integers(1, 20_000_000), max_size=12, unique=True).map(sorted),
)
_random = st.builds(
    RandomEdges,
    seed=st.integers(0, 50),
    mean_interval_us=st.integers(5_000, 800_000),
    min_interval_us=st.just(1_000),
)
_step = st.one_of(
    st.tuples(st.just("signal"), st.tuples(st.integers(0, 15), st.one_of(_pulse, _edges, _random))),
    st.tuples(st.just("advance"), st.integers(1, 3_000_000)),
    st.tuples(st.just("advance"), st.integers(3_000_000, 200_000_000)),
    st.tuples(st.just("read"), st.just(0)),
    st.tuples(st.just("filter"), st.tuples(st.integers(0, 1), st.sampled_from([0, 1, 2, 7, 40]))),
    st.tuples(st.just("pair"), st.tuples(st.integers(0, 383), st.integers(0, 0xFFFF))),
    st.tuples(st.just("set"), st.tuples(st.integers(0, 15), st.booleans())),
    st.tuples(st.just("power"), st.just(0)),
)


def _tes(model: str, lazy: bool) -> Tes:
    tes = Tes(model)
    tes.di.lazy = lazy
    return tes


def _observe(tes: Tes) -> list[object]:
    tes.di.sync()
    now = tes.clock.now
    count = tes.model.digital_inputs
    return [
        [tes.registers.peek(r, now) for r in tes.registers.table.values()],
        [tes.di.direct(i) for i in range(count)],
        [tes.di.filtered(i) for i in range(count)],
        tes.di.changes_pending,
        [_state(inp) for inp in tes.di._inputs],
    ]


def _state(inp: object) -> tuple[object, ...]:
    """Everything an input holds, its pending confirmation as (time, state)."""
    from fieldtwin.tes.digital import _Input

    assert isinstance(inp, _Input)
    if inp.pending is not None and inp.pending.active:
        pending: tuple[int, bool] | None = (inp.pending.time, inp.direct)
    else:
        pending = None if inp.pending_at is None else (inp.pending_at, inp.pending_value)
    fields = (inp.contact, inp.wiring, inp.direct, inp.filtered, inp.memorized, inp.changes)
    return (*fields, inp.rise, inp.fall, inp.since, inp.bias, *inp.last, *inp.cumulated, pending)


def _apply(tes: Tes, step: tuple) -> object:  # type: ignore[type-arg]
    kind, arg = step
    now = tes.clock.now
    if kind == "signal":
        tes.set_signal(arg[0], arg[1], True)
    elif kind == "advance":
        tes.clock.advance(arg)
    elif kind == "read":  # a master read of every word: memorized inputs restored
        table = list(tes.registers.table.values())
        return [tes.execute(ReadWords(3, r.address, 1), Link.RS485, now, False) for r in table]
    elif kind == "filter":
        return tes.execute(WriteWord(0x00A + arg[0], arg[1]), Link.RS485, now, False)
    elif kind == "pair":
        pairs = [r for r in tes.registers.table.values() if r.kind in PAIRS]
        reg = pairs[arg[0] % len(pairs)]
        return tes.execute(WriteWord(reg.address, arg[1]), Link.RS485, now, False)
    elif kind == "set":
        tes.set_input(arg[0], arg[1])
    elif kind == "power":
        tes.power_cycle()
    elif kind == "wiring":
        tes.set_wiring(arg[0], arg[1])
    return None


def _live(steps: list[tuple], model: str) -> None:  # type: ignore[type-arg]
    lazy, ref = _tes(model, True), _tes(model, False)
    for step in steps:
        assert _apply(lazy, step) == _apply(ref, step), step
        assert _observe(lazy) == _observe(ref), step
    assert lazy.clock.now == ref.clock.now


@settings(max_examples=150, deadline=None)
@given(st.lists(_step, min_size=1, max_size=30))
@example([("signal", (0, PulseTrain(1_000_000))), ("advance", 100 * S), ("read", 0)])
@example(
    [  # a pulse as long as its filter: the confirmation comes first, then the edge
        ("filter", (1, 2)),
        ("signal", (3, PulseTrain(20_000, duty=0.5))),
        ("advance", 61 * S),
        ("read", 0),
        ("filter", (0, 40)),
        ("advance", 5 * S),
        ("read", 0),
    ]
)
def test_inputs_followed_at_read_time_read_as_an_event_per_edge(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    _live(steps, "TES 32EST")


_wiring = st.tuples(
    st.just("wiring"), st.tuples(st.integers(0, 15), st.sampled_from(["ok", "short", "open"]))
)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(_step, _wiring), min_size=1, max_size=25))
def test_the_same_with_wiring_faults_on_a_tes_32et_s(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    _live(steps, "TES 32ET-S")


def test_a_followed_input_costs_no_event_per_edge_and_the_beat_keeps_the_clock_busy() -> None:
    tes = Tes("TES 32EST")
    tes.set_signal(0, PulseTrain(10_000), True)  # 200 edges per second
    fired = tes.clock.fired
    tes.clock.advance(100 * S)
    assert tes.clock.fired - fired == 100  # the beat, once a second: nothing per edge
    assert tes.clock.next_deadline() == 101 * S
    now = tes.clock.now
    rises = tes.registers.get_words([tes.registers.table[0x025], tes.registers.table[0x026]], now)
    # rises at 0, 10 ms ... 99.99 s confirmed; the one at 100 s is still in its filter
    assert (rises[0] << 16) | rises[1] == 10_000
    tes.set_input(0, False)  # no signal any more: nothing left to follow, no beat
    assert tes.di.followed == 0
    assert tes.clock.next_deadline() is None


def test_a_signal_that_stops_changing_is_followed_no_more() -> None:
    tes = Tes("TES 32EST")
    tes.set_signal(2, Edges(False, [1_000, 2_000_000]), True)
    tes.clock.advance(70 * S)  # a beat catches it up: its last edge is behind it
    assert tes.di.followed == 0 and Beat.of(tes.clock).members == 0
    assert tes.di.filtered(2) is False and tes.di.value32("counter_rise", 2, tes.clock.now) == 1


def test_the_reference_has_an_event_per_edge() -> None:
    assert DigitalInputs.lazy is True
    tes = _tes("TES 32EST", False)
    tes.set_signal(0, PulseTrain(10_000), True)
    fired = tes.clock.fired
    tes.clock.advance(1 * S)
    assert tes.clock.fired - fired >= 400  # 200 edges and their 200 confirmations


def test_a_tes_with_followed_inputs_is_freed_with_its_clock() -> None:
    import gc
    import weakref

    clocks = []
    for _ in range(3):
        tes = Tes("TES 32EST")
        tes.set_signal(0, PulseTrain(10_000), True)
        tes.clock.advance(3 * S)
        clocks.append(weakref.ref(tes.clock))
        del tes
    gc.collect()
    assert all(ref() is None for ref in clocks)  # the beat lives on its clock, not beside it
