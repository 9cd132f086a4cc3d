"""A TES analog channel sampled lazily reads as one sampled by a clock event each time.

Two TES 8EA live the same random history, one sampling lazily where no judgement
can change (``AnalogInputs.lazy``, the default), one with a clock event per sample
(the reference): sine, square, ramp, noise and constant inputs, inputs changed,
time in steps of every length, master writes of thresholds (out of reach, the
default, and within reach: the alarms and reflex outputs then matter), of threshold
outputs, polarity, the storage period and the status word (a reset of the latched
alarms), reads, power cycles.  After every step both read the same in every register
(values, channel states, status, the stored history) and drive the same outputs.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.modbus.model import Link, WriteWord
from fieldtwin.signals import Constant, Noise, Ramp, Sine, Square
from fieldtwin.tes import Tes

_write = st.one_of(
    st.tuples(st.integers(0x023, 0x032), st.sampled_from([0x8000, 0x7FFF, 0, 300, 700, 1023])),
    st.tuples(st.integers(0x033, 0x03A), st.sampled_from([0x0100, 0x0202, 0xFFFF])),
    st.tuples(st.just(0x03B), st.integers(0, 15)),  # polarity
    st.tuples(st.just(0x055), st.integers(0, 3)),  # storage period (Tb = 1 s)
    st.tuples(st.just(0x000), st.sampled_from([0, 0x40, 0x80])),  # latches reset
)
_signal = st.sampled_from(["sine", "square", "ramp", "noise", "level"])
_step = st.one_of(
    st.tuples(st.just("advance"), st.integers(1, 400_000)),
    st.tuples(st.just("advance"), st.integers(1, 20).map(lambda k: k * 1_000_000)),
    st.tuples(st.just("write"), _write),
    st.tuples(st.just("signal"), st.tuples(st.integers(0, 7), _signal)),
    st.tuples(st.just("power"), st.just(0)),
)


def _signal_of(kind: str, k: int) -> object:
    if kind == "sine":
        return Sine(5.0, 4.5, 300_000 * (k + 1))
    if kind == "square":
        return Square(1.0, 9.0, 200_000 * (k + 1))
    if kind == "ramp":
        return Ramp(0.0, 10.0, 0, 5_000_000 * (k + 1))
    if kind == "noise":
        return Noise(Constant(5.0), 0.5, seed=k, sample_period_us=100_000)
    return None


def _tes(lazy: bool) -> Tes:
    tes = Tes("TES 8EA")
    tes.ai.lazy = lazy
    for k in range(8):
        signal = _signal_of(("sine", "square", "ramp", "noise")[k % 4], k)
        tes.set_signal(f"a{k}", signal)  # type: ignore[arg-type]
    return tes


def _map(tes: Tes) -> list[int]:
    return [tes.registers.peek(r, tes.clock.now) for r in tes.registers.table.values()]


def _outputs(tes: Tes) -> list[bool]:
    return [tes.digital_output(o) for o in range(4)]


def _apply(tes: Tes, step: tuple) -> None:  # type: ignore[type-arg]
    kind, arg = step
    if kind == "advance":
        tes.clock.advance(arg)
    elif kind == "write":
        address, value = arg
        tes.execute(WriteWord(address, value), Link.RS485, tes.clock.now, False)
    elif kind == "signal":
        k, what = arg
        signal = _signal_of(what, k)
        if signal is None:
            tes.set_input(k, 2.5 + k)
        else:
            tes.set_signal(f"a{k}", signal)  # type: ignore[arg-type]
    else:
        tes.power_cycle()


@settings(max_examples=60)
@given(st.lists(_step, min_size=1, max_size=25))
def test_lazy_samples_read_as_sampled_at_every_slot(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    lazy, ref = _tes(True), _tes(False)
    for step in steps:
        for tes in (lazy, ref):
            _apply(tes, step)
        assert lazy.ram.status == ref.ram.status, step  # before any read catches up
        assert _map(lazy) == _map(ref), step
        assert _outputs(lazy) == _outputs(ref), step
        assert lazy.do.reflex == ref.do.reflex, step
        assert [ch.history for ch in lazy.ai.channels.values()] == [
            ch.history for ch in ref.ai.channels.values()
        ], step


def test_the_default_thresholds_leave_every_varying_channel_lazy() -> None:
    lazy, ref = _tes(True), _tes(False)
    for tes in (lazy, ref):
        tes.clock.advance(10_000_000)
    assert _map(lazy) == _map(ref)
    # eight channels sampled every 64 ms by the reference; the lazy TES: its first
    # samples, then the beat once a second
    assert ref.clock.fired > 1_200
    assert lazy.clock.fired < 100
