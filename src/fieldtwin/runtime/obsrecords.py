"""The raw records the simulation's thread hands the observers (fieldtwin.runtime.events):
plain data, so that a process of the observers' own can take them (obslink, obsproc).

A record is ``(op, *args)``; a wiretap's stream is named by its number (``attach``),
a wiretap by its number and rebuilt from its ``spec()`` in the observers' process.
``Event`` is what the records become (re-exported by fieldtwin.runtime.events).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import orjson

# as Starlette's send_json: compact, not ASCII-escaped (one encoder, made once)
_ENCODE = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False).encode
_DUMPS = orjson.dumps

# The kinds whose data are made of strings, integers, booleans, None and lists or
# dicts of those, never a float (the wiretaps' and the character taps' own fields:
# tests/trace/test_fast_json.py checks them over random traffic).  Their JSON is
# written by orjson (a C encoder, about 15 times cheaper than json's), which writes
# such values exactly as json does with ``ensure_ascii=False``; it writes some floats
# differently (``0.00001`` for json's ``1e-05``), so the times are written with
# ``repr`` as json writes them, and any other value, or kind, goes through json.
PLAIN_KINDS = frozenset(("modbus", "serial", "connection", "register"))
_PLAIN = frozenset((str, int, bool, type(None)))
_NESTED = frozenset((list, tuple, dict))
_ALLOWED = _PLAIN | _NESTED


def _plain(values: Iterable[object]) -> bool:
    """No value in ``values`` (nor in the lists and dicts among them) is other than a
    string, an integer, a boolean or None."""
    values = tuple(values)
    types = set(map(type, values))
    if types <= _PLAIN:
        return True
    if not types <= _ALLOWED:
        return False
    for value in values:
        if type(value) in _NESTED and not _plain(
            value.values() if isinstance(value, dict) else value  # type: ignore[arg-type]
        ):
            return False
        if isinstance(value, dict) and not set(map(type, value)) <= {str}:
            return False
    return True


def plain_body(kind: str, device: str, data: Mapping[str, object]) -> bytes | None:
    """``{"kind":…,"device":…,**data}`` as compact JSON by orjson when ``kind`` is a
    plain kind and every value plain; None: json must write it."""
    if kind not in PLAIN_KINDS or not _plain(data.values()):
        return None
    try:
        return _DUMPS({"kind": kind, "device": device, **data})
    except (TypeError, orjson.JSONEncodeError):  # a key not a string, an integer too big
        return None


def event_json(t_us: int, kind: str, device: str, data: Mapping[str, object]) -> str:
    """An event as ``Event.json`` writes it: ``{"t_s":…,"kind":…,"device":…,**data}``,
    compact, not ASCII-escaped (as Starlette's ``send_json``)."""
    body = plain_body(kind, device, data) if "t_s" not in data else None
    if body is None:
        return _ENCODE({"t_s": t_us / 1e6, "kind": kind, "device": device, **data})
    return '{"t_s":' + repr(t_us / 1e6) + "," + body[1:].decode()


def template(
    kind: str, device: str, data: Mapping[str, object], cut: str
) -> tuple[str, str] | None:
    """A frame's JSON body cut around its two per-frame fields: ``(head, tail)`` with
    ``head + str(number) + ',"hex":"' + hex + tail`` the text ``plain_body`` writes
    (from after its opening brace) for ``data`` with ``data[cut] = number`` and
    ``data["hex"] = hex``, the key ``cut`` directly followed by ``"hex"``; None when
    ``plain_body`` would not write it (fieldtwin.runtime.wiretap's remembered frames)."""
    keys = list(data)
    at = keys.index(cut) if cut in data else -1
    if at < 0 or keys[at + 1 : at + 2] != ["hex"] or {"t", "wall", "t_s"} & set(keys):
        return None
    head = dict(list(data.items())[:at])
    rest = dict(list(data.items())[at + 2 :])
    first = plain_body(kind, device, head)
    last = plain_body(kind, device, rest)
    if first is None or last is None:
        return None
    tail = last[len(_DUMPS({"kind": kind, "device": device})) - 1 :].decode()  # "}" or ",…}"
    return first[1:-1].decode() + ',"' + cut + '":', '"' + tail


@dataclass(slots=True)
class Event:
    """One thing that happened: when (simulated us), what kind, on which device, its fields.

    Treated as a value, never changed once made (not a frozen dataclass only because a
    frozen one's ``__init__`` costs three times as much, once per frame observed).
    ``body``, when its maker knows it, is its JSON but the time: ``plain_body``'s text
    after the opening brace (a wiretap's frame, made from a remembered template)."""

    t_us: int
    kind: str  # "modbus", "serial", "object", "led", "dem", "register", "clock", ...
    device: str  # the device's address as the Device face writes it ("5", "tcp://...:5020 1")
    data: Mapping[str, object]
    body: str | None = field(default=None, compare=False, repr=False)
    _json: str | None = field(default=None, compare=False, repr=False)

    def as_dict(self) -> dict[str, object]:
        return {"t_s": self.t_us / 1e6, "kind": self.kind, "device": self.device, **self.data}

    def json(self) -> str:
        """``as_dict()`` as compact JSON (as Starlette's ``send_json`` writes it), made
        once however many subscribers send it."""
        text = self._json
        if text is None:
            body = self.body
            if body is None:
                text = event_json(self.t_us, self.kind, self.device, self.data)
            else:
                text = '{"t_s":' + repr(self.t_us / 1e6) + "," + body
            self._json = text
        return text


MAX_STREAMS = 4096  # wiretap streams remembered by number (the oldest forgotten)

# A raw record is plain data: ``(op, *args)``.  The data records (the hot path):
OP_EVENT = 0  # (OP_EVENT, t_us, kind, device, data): an event as published
OP_IN = 1  # (OP_IN, stream, bytes, now, states): a chunk arrived (wiretap.Stream)
OP_POLL = 2  # (OP_POLL, stream, now, states): the core was polled
OP_OUT = 3  # (OP_OUT, stream, bytes, now): a transmission
OP_REJECTED = 4  # (OP_REJECTED, stream, bytes, now, reason, note, fault)
# ... and the control records, never refused by a full buffer:
OP_FORGET = 5  # (OP_FORGET, stream): its connection closed
OP_TAP = 6  # (OP_TAP, tap, spec): a wiretap, as the observers' process rebuilds it
OP_STREAM = 7  # (OP_STREAM, stream, tap, conn)
OP_SUB = 8  # (OP_SUB, number, kinds, devices, maxlen): a subscription in the process
OP_UNSUB = 9  # (OP_UNSUB, number)
OP_WRITE = 10  # (OP_WRITE, "trace" | "pcap", path, start_wall): a file the process writes
STREAM_OPS = {OP_IN: "inbound", OP_POLL: "poll", OP_OUT: "outbound", OP_REJECTED: "rejected"}


class Tapped(Protocol):
    """A wiretap's stream as the bus knows it (fieldtwin.runtime.wiretap.Stream)."""

    conn: str

    @property
    def tap(self) -> Any: ...


class Link(Protocol):
    """The observers' process as the bus drives it (fieldtwin.runtime.obslink)."""

    alive: bool

    def ship(self, batch: list[tuple[Any, ...]], lost: int) -> None: ...

    def subscribe(
        self,
        kinds: Collection[str] | None,
        devices: Collection[str] | None,
        maxlen: int,
        notify: Callable[[], None] | None,
    ) -> Any: ...

    def write(self, kind: str, path: str, start_wall: float | None = None) -> None: ...

    def close(self) -> None: ...
