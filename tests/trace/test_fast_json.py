"""The observers' JSON written by orjson is the JSON json writes, character for
character: the ``/events`` texts (``ensure_ascii=False``, as Starlette's
``send_json``) and the trace lines (``ensure_ascii=True``), for every kind and value
(fieldtwin.runtime.obsrecords ``event_json``, fieldtwin.runtime.trace ``line``)."""

from __future__ import annotations

import json
import os

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.runtime.events import Event, EventBus
from fieldtwin.runtime.obsrecords import PLAIN_KINDS, event_json, plain_body
from fieldtwin.runtime.trace import line, record
from tests.trace.test_pcap_raw import _drive, steps

EXAMPLES = 20 if os.environ.get("FIELDTWIN_FAST_EXAMPLES") else 200
SEND_JSON = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False).encode
TRACE_JSON = json.JSONEncoder(separators=(",", ":")).encode

texts = st.text(st.characters(codec="utf-8"), max_size=12) | st.text(
    st.characters(max_codepoint=255), max_size=12
)
scalars = st.none() | st.booleans() | st.integers(-(2**70), 2**70) | texts
values = st.recursive(
    scalars | st.floats(allow_nan=False, allow_infinity=False),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(texts, inner, max_size=4),
    max_leaves=8,
)
kinds = st.sampled_from([*sorted(PLAIN_KINDS), "led", "object", "dem", "clock"])
times = st.integers(0, 10**13)


def _as_json(event: Event) -> str:
    return SEND_JSON(event.as_dict())


@settings(max_examples=EXAMPLES, deadline=None)
@given(
    t_us=times,
    kind=kinds,
    device=texts,
    data=st.dictionaries(texts, values, max_size=6),
    wall=st.floats(0, 4e9),
)
def test_any_event_is_written_as_json_writes_it(
    t_us: int, kind: str, device: str, data: dict[str, object], wall: float
) -> None:
    event = Event(t_us, kind, device, data)
    assert event_json(t_us, kind, device, data) == _as_json(event)
    assert event.json() == _as_json(event)
    assert line(event, repr(round(wall, 6))) == TRACE_JSON(record(event, round(wall, 6)))


@settings(max_examples=EXAMPLES, deadline=None)
@given(steps=steps)
def test_the_wires_events_are_written_by_orjson_as_json_writes_them(steps: list) -> None:
    bus = EventBus()
    sub = bus.subscribe()
    _drive(bus, steps)
    for event in sub.take(100_000):
        assert event.kind in PLAIN_KINDS
        assert plain_body(event.kind, event.device, event.data) is not None  # the fast way
        assert event.json() == _as_json(event)
        assert line(event, "1700000000.25") == TRACE_JSON(record(event, 1700000000.25))


def test_a_float_or_another_kind_goes_through_json() -> None:
    assert plain_body("modbus", "d", {"x": 0.00005}) is None  # orjson: 0.00005, json: 5e-05
    assert plain_body("led", "d", {"x": 1}) is None
    assert plain_body("modbus", "d", {"x": 2**64}) is None  # too big for orjson
    assert (
        event_json(50, "modbus", "d", {"x": 1})
        == '{"t_s":5e-05,"kind":"modbus","device":"d","x":1}'
    )


@settings(max_examples=EXAMPLES, deadline=None)
@given(
    item=st.lists(scalars | st.binary(max_size=20) | st.floats(allow_nan=False), max_size=6),
    kind=st.sampled_from(["data", "send", "result", "end"]),
)
def test_a_recordings_line_is_written_as_json_writes_it(item: list[object], kind: str) -> None:
    from fieldtwin.runtime.recwriter import _line, _plain

    record = [kind, *item]
    text = json.dumps(record, separators=(",", ":"), ensure_ascii=False, default=_plain)
    assert _line(record) == text.encode("utf-8") + b"\n"
