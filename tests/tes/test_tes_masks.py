"""Issue 25 item 2: the TES's bit words built at once equal the bit-by-bit reference.

``DigitalOutputs.mask`` (fixed command bits at once, then blinking outputs, then
reflex overrides) against ``state`` of each output; ``DigitalInputs.bits`` for
every input word against the inputs' own states.
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import SimClock
from fieldtwin.tes import Tes
from fieldtwin.tes.outputs import DigitalOutputs


@given(
    st.integers(0, 32),
    st.integers(0, 0xFFFFFFFF),
    st.integers(0, 0xFFFFFFFF),
    st.dictionaries(st.integers(-2, 40), st.booleans(), max_size=6),
    st.lists(st.integers(0, 20), min_size=4, max_size=4),
    st.integers(0, 10**7),
)
def test_output_mask_is_each_outputs_state(
    count: int, command: int, blink: int, reflex: dict[int, bool], words: list[int], now: int
) -> None:
    outputs = DigitalOutputs(count, lambda i: words[i])
    outputs.command, outputs.blink_select = command, blink
    outputs.reflex.update(reflex)
    expected = sum(1 << i for i in range(count) if outputs.state(i, now))
    assert outputs.mask(now) == expected


@given(
    st.sampled_from(("32EST", "16EST", "32ET")), st.lists(st.booleans(), min_size=32, max_size=32)
)
def test_input_bit_words_are_the_inputs(model: str, levels: list[bool]) -> None:
    tes = Tes(model, 1, clock=SimClock())
    di = tes.di
    for i, level in enumerate(levels[: tes.model.digital_inputs]):
        tes.set_input(i, level)
    tes.advance(1.0)
    for word in range((tes.model.digital_inputs + 15) // 16):
        for attr in ("direct", "filtered", "memorized"):
            states = [
                getattr(di._inputs[i], attr)
                for i in range(16 * word, 16 * word + 16)
                if i < len(di._inputs)
            ]
            assert di.bits(attr, word) == sum(1 << b for b, on in enumerate(states) if on)
