"""A TCP frame published from what its stream remembers is the frame the general
framing and decoding publish: the same events (fields, order, time, device), the same
``/events`` JSON and the same trace lines, byte for byte, over random traffic (cut
chunks, garbage, writes, exceptions, other units, TES states that change, a decoding
subscriber that comes and goes, more frames than the memo holds).
``Stream.fast = False`` is the reference (fieldtwin.runtime.wiretap)."""

from __future__ import annotations

import os

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.runtime import wiretap
from fieldtwin.runtime.events import Event, EventBus
from fieldtwin.runtime.trace import line
from fieldtwin.runtime.wiretap import Stream, Wiretap
from tests.trace.test_pcap_raw import PDUS, _mbap

EXAMPLES = 30 if os.environ.get("FIELDTWIN_FAST_EXAMPLES") else 150
ROSTER = ((1, "TES #1"), (2, "TES é2"))  # a name outside ASCII: the trace escapes it
STATES = [None, (False, False, None, 0), (True, True, None, 0), (True, False, None, 4000)]

# requests and replies that come back often (the same function's replies to two
# different reads, two exceptions), and the rarer others
REQUESTS = [PDUS[0], bytes.fromhex("0300000002"), PDUS[2]]
REPLIES = [PDUS[1], bytes.fromhex("8302"), bytes.fromhex("8304"), PDUS[2]]
ALL_PDUS = [*PDUS, *REQUESTS, *REPLIES, bytes.fromhex("0f0000000a0203ff"), bytes.fromhex("16")]
steps = st.lists(
    st.tuples(
        st.sampled_from(["exchange"] * 4 + ["in", "out", "sub", "unsub"]),
        st.integers(0, 3) | st.integers(0, 0xFFFF),  # transaction: often the same
        st.just(1) | st.sampled_from([1, 2, 0, 7, 0xFF]),  # unit: often the same
        st.sampled_from(REQUESTS) | st.sampled_from(ALL_PDUS),
        st.sampled_from(REPLIES) | st.sampled_from(ALL_PDUS),
        st.sampled_from([0, 0, 0, 0, 1, 2, 3, 4]),  # whole, split, two frames, garbage, begun
        st.tuples(st.sampled_from(STATES[:2]), st.just(None))
        | st.tuples(st.sampled_from(STATES), st.sampled_from(STATES)),
        st.just(0) | st.integers(0, 1),  # the connection
    ),
    min_size=20,
    max_size=80,
)


def _chunks(framed: bytes, cut: int, again: bytes) -> list[bytes]:
    if cut == 1:
        return [framed[:5], framed[5:]]
    if cut == 2:
        return [framed + again]
    if cut == 3:
        return [b"\x00\x01\x00\x07" + framed[:3]]  # a bad length: an error event
    if cut == 4:
        return [framed[:7]]  # a frame begun: the next chunk completes it
    return [framed]


def _run(steps: list, fast: bool) -> tuple[list[Event], list[str], list[str]]:
    bus = EventBus()
    # every event, decoded or not (``raw`` does not make the wiretaps decode); a
    # decoding subscriber comes and goes ("sub", "unsub")
    seen = bus.subscribe(maxlen=100_000, raw=True)
    decoding = [bus.subscribe(maxlen=100_000)]
    tap = Wiretap(bus, "tcp://127.0.0.1:5020", "tcp", None, None, "tcp://127.0.0.1:5020", ROSTER)
    conns = [tap.stream(f"127.0.0.1:{40000 + n}") for n in range(2)]
    for n, (what, transaction, unit, request, reply, cut, states, conn) in enumerate(steps):
        stream = conns[conn]
        stream.fast = fast
        if what == "sub":
            if not decoding:
                decoding.append(bus.subscribe(maxlen=100_000))
            continue
        if what == "unsub":
            if decoding:
                decoding.pop().close()
            continue
        again = (transaction + 1) & 0xFFFF
        if what in ("in", "exchange"):
            for chunk in _chunks(
                _mbap(transaction, unit, request), cut, _mbap(again, unit, request)
            ):
                stream.inbound(chunk, 1000 * n, states)
        if what in ("out", "exchange"):
            cut = 0 if what == "exchange" else cut
            for chunk in _chunks(_mbap(transaction, unit, reply), cut, _mbap(again, unit, reply)):
                stream.outbound(chunk, 1000 * n + 500)
    events = seen.take(100_000)
    texts = [event.json() for event in events]
    lines = [line(event, "1700000000.25") for event in events]
    return events, texts, lines


@pytest.fixture(autouse=True)
def _small_memo(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(wiretap, "MEMO", 12)  # forgotten often: learnt again, same frames


@settings(max_examples=EXAMPLES, deadline=None)
@given(steps=steps)
def test_remembered_frames_are_the_frames_the_general_decoding_publishes(steps: list) -> None:
    fast, fast_texts, fast_lines = _run(steps, fast=True)
    slow, slow_texts, slow_lines = _run(steps, fast=False)
    assert [(e.t_us, e.kind, e.device, list(e.data.items())) for e in fast] == [
        (e.t_us, e.kind, e.device, list(e.data.items())) for e in slow
    ]
    assert fast_texts == slow_texts
    assert fast_lines == slow_lines


def test_a_poll_is_remembered_and_its_events_keep_their_own_numbers() -> None:
    bus = EventBus()
    sub = bus.subscribe()
    tap = Wiretap(bus, "tcp://x", "tcp", None, None, "tcp://1.2.3.4:5", ROSTER)
    stream = tap.stream("c")
    for transaction in (1, 2):
        stream.inbound(_mbap(transaction, 1, PDUS[0]), transaction, (None, None))
        stream.outbound(_mbap(transaction, 1, PDUS[1]), transaction)
    assert len(stream._memo) == 2  # one request, one reply, each learnt once
    events = sub.take()
    assert [e.data["transaction"] for e in events] == [1, 1, 2, 2]
    assert all(e.body is not None for e in events)  # the JSON made from the template
    assert [e.data["hex"][:4] for e in events] == ["0001", "0001", "0002", "0002"]
    assert events[1].data["address"] == 37 and events[1].data["from"] == "TES #1"
    assert Stream.fast
