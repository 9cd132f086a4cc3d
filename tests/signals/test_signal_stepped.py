"""Issue 15: the one-search answers of discrete signals and the faster seeded draws.

``value_and_next(t)`` is ``(value_at(t), next_change(t))``; ``UniformStream`` draws
bit-identical values to :func:`uniform`; the edges of ``RandomEdges`` are the ones
its definition gives (min interval + exponential draw of ``uniform(seed, "edges", k)``),
whatever order the times are asked in and however far ahead the cache was drawn.
"""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.signals import Edges, RandomEdges
from fieldtwin.signals.base import SteppedSignal, UniformStream, uniform

_times = st.lists(st.integers(0, 3_000_000), min_size=1, max_size=40)


@given(st.integers(-(10**15), 10**15), st.text(max_size=8), st.integers(0, 10**9))
def test_uniform_stream_draws_the_same_bits(seed: int, stream: str, index: int) -> None:
    assert UniformStream(seed, stream)(index) == uniform(seed, stream, index)


def _reference_edges(seed: int, mean: int, minimum: int, until: int) -> list[int]:
    """The edge times by the definition, with ``uniform`` itself."""
    edges: list[int] = []
    last = 0
    while last <= until:
        draw = -math.log(uniform(seed, "edges", len(edges))) * (mean - minimum)
        last += minimum + round(draw)
        edges.append(last)
    return edges


@given(
    st.integers(-1000, 10**6),
    st.sampled_from([(1_000, 1_000), (1_000, 5_000), (700, 20_000), (50_000, 300_000)]),
    st.booleans(),
    _times,
)
def test_random_edges_answer_by_their_definition(
    seed: int, intervals: tuple[int, int], initial: bool, times: list[int]
) -> None:
    minimum, mean = intervals
    signal = RandomEdges(seed, mean, minimum, initial)
    fresh = RandomEdges(seed, mean, minimum, initial)
    reference = _reference_edges(seed, mean, minimum, max(times))
    assert isinstance(signal, SteppedSignal)
    for t in times:  # any order: the cache is drawn ahead, the answers do not move
        value, nxt = signal.value_and_next(t)
        assert (value, nxt) == (fresh.value_at(t), fresh.next_change(t))
        passed = sum(1 for e in reference if e <= t)
        assert value == initial ^ (passed % 2 == 1)
        assert nxt == reference[passed]
    cached = signal._edges
    assert cached[: len(reference)] == reference[: len(cached)]


@given(st.booleans(), st.lists(st.integers(1, 50_000), max_size=12), _times)
def test_edges_value_and_next(initial: bool, gaps: list[int], times: list[int]) -> None:
    edge_times, t = [], 0
    for gap in gaps:
        t += gap
        edge_times.append(t)
    signal = Edges(initial, edge_times)
    assert isinstance(signal, SteppedSignal)
    for t in times + edge_times:
        assert signal.value_and_next(t) == (signal.value_at(t), signal.next_change(t))
