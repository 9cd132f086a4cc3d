"""IWxy,6/7 (the accepted input levels) kept as a bit vector, checked against the channels."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS
from fieldtwin.facade import inject_fault
from tests.tsx.dem24.helpers import SLOT, make

steps = st.lists(
    st.tuples(
        st.integers(0, 23),
        st.sampled_from([True, False, 3.0, 24.0]),
        st.integers(0, 3),
        st.sampled_from(["level", "terminal_block", "supply", "power"]),
    ),
    max_size=40,
)


@settings(max_examples=25, deadline=None)
@given(steps)
def test_the_input_image_is_the_levels_of_the_24_channels(
    moves: list[tuple[int, bool | float, int, str]],
) -> None:
    plc, mod = make()
    for channel, value, gap_ms, what in moves:
        if what == "level":
            mod.set_input(channel, value)
        elif what == "power":
            plc.power_break(0.001 * gap_ms)
        else:
            inject_fault(mod, what, bool(channel % 2))
        plc.clock.run_until(plc.clock.now + gap_ms * MS)
    plc.advance(12.0)  # any self-test over, filters settled
    levels = sum(int(mod.inputs.level(i)) << i for i in range(24))
    assert mod.inputs.levels() == levels
    if mod.running and mod.terminal_block:
        assert plc.read(f"IW{SLOT},6") | (plc.read(f"IW{SLOT},7") << 16) == levels
