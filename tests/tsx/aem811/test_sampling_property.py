"""A property of the sampling machine (AEM 2.2-4, 4.1-4) under any command sequence.

Random writes of OWxy,1 (inhibit bits and accelerated mode) and OWxy,0,C at random
instants; after each step: an acquisition never starts while another is running,
each value reaches its register exactly 100 ms after its sampling, an inhibited
channel is never sampled, its detection bits are 0, and each register word shows
the channel its selector bit names (or 0 when both channels are inhibited).
"""

from __future__ import annotations

from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS
from fieldtwin.tsx.aem811 import Aem811
from tests.tsx.aem811.helpers import ready

steps = st.lists(
    st.tuples(
        st.sampled_from(["ow1", "run", "wait"]),
        st.integers(0, 0x1FF),
        st.sampled_from([10, 50, 100, 130, 300, 1000]),
    ),
    min_size=1,
    max_size=25,
)


def spy(mod: Aem811, log: list[tuple[str, int, int]]) -> None:
    begin, publish = mod._begin, mod._publish

    def on_begin(slot: Any, now: int) -> None:
        assert mod._acquiring is None, "an acquisition started while one runs"
        assert mod.enabled >> slot.channel & 1, "an inhibited channel was sampled"
        log.append(("begin", now, slot.channel))
        begin(slot, now)

    def on_publish(done: Any, now: int) -> None:
        assert now - done.start == 100 * MS
        log.append(("publish", now, done.channel))
        publish(done, now)

    mod._begin = on_begin  # type: ignore[method-assign]
    mod._publish = on_publish  # type: ignore[method-assign]


def check_registers(mod: Aem811) -> None:
    enabled = mod.enabled
    for index in range(4):
        channel = index + 4 * (mod.iw[2] >> index & 1)
        value = mod.iw[3 + index]
        if enabled >> channel & 1:
            assert value == mod.values[channel] & 0xFFFF
        else:  # forced to 0; a re-enabled partner takes over at its first value
            assert value == 0 and mod.values[channel ^ 4] == 0
    for channel in range(8):
        if not enabled >> channel & 1:
            assert not mod.i_bits >> channel & 1 and not mod.i_bits >> (channel + 8) & 1
            assert not mod.iw[1] >> (8 + channel) & 1
    assert mod.iw[1] & 0xFF == ~enabled & 0xFF


@settings(max_examples=40, deadline=None)
@given(steps)
def test_sampling_invariants(sequence: list[tuple[str, int, int]]) -> None:
    plc, mod = ready(quantize=False)
    for channel in range(8):
        mod.set_input(channel, volts=channel - 3.5)
    log: list[tuple[str, int, int]] = []
    spy(mod, log)
    plc.write("OW5,0,C", 1)
    for kind, value, wait_ms in sequence:
        if kind == "ow1":
            plc.write("OW5,1", value)
        elif kind == "run":
            plc.write("OW5,0,C", value & 1)
        plc.advance(wait_ms / 1000)
        check_registers(mod)
    begun = sum(1 for what, _, _ in log if what == "begin")
    assert begun == sum(mod.relay_operations)  # one relay operation per acquisition
