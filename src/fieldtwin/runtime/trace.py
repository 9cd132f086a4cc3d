"""The traffic trace: one JSON line per Modbus frame or block of SCM characters.

``TraceWriter`` subscribes to the plant's event bus (kinds ``modbus`` and
``serial``) and writes each event as it is published, into a buffered file
that is flushed on ``close``.  The plant never waits for it: a full disk or a
closed file is reported once, tracing stops, the plant keeps running; when the
writer falls behind (it cannot, it writes on the simulation's thread, but the
subscription is bounded anyway) the events lost are counted in the last line
of the report.  ``describe`` turns one record into the line people read
(``fieldtwin trace show``, the console's ``trace`` command).  Format: docs/trace.md.
"""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable, Collection, Mapping
from pathlib import Path

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import Event, EventBus, Subscription
from fieldtwin.runtime.obsrecords import plain_body

TRACE_KINDS = ("modbus", "serial")
BUFFER = 64 * 1024  # bytes the file buffers before it writes (and on close)
QUEUE = 10_000  # events the subscription holds (the writer drains it on every event)

Report = Callable[[str], None]
_ENCODE = json.JSONEncoder(separators=(",", ":")).encode  # as json.dumps(..., separators)


def line(event: Event, wall: str) -> str:
    """``record(event, wall)`` as its JSON line (without the newline), ``wall`` given as
    ``repr(round(wall, 6))``: the same text as json writes (``ensure_ascii``), by
    orjson where it writes the same (fieldtwin.runtime.obsrecords.plain_body)."""
    known = event.body  # a remembered frame's: never a "t" nor a "wall" in it
    if known is not None and known.isascii() and "\x7f" not in known:
        return '{"t":' + repr(round(event.t_us / 1e6, 6)) + ',"wall":' + wall + "," + known
    data = event.data
    if known is None and "t" not in data and "wall" not in data:
        body = plain_body(event.kind, event.device, data)
        if body is not None and body.isascii() and b"\x7f" not in body:
            return (
                '{"t":'
                + repr(round(event.t_us / 1e6, 6))
                + ',"wall":'
                + wall
                + ","
                + body[1:].decode()
            )
    return _ENCODE(record(event, float(wall)))


def record(event: Event, wall: float) -> dict[str, object]:
    """The JSON object of one event: simulated and wall time first, then its fields."""
    return {
        "t": round(event.t_us / 1e6, 6),
        "wall": round(wall, 6),
        "kind": event.kind,
        "device": event.device,
        **event.data,
    }


class TraceWriter:
    """Writes the traffic published on ``bus`` to ``path`` as JSON lines."""

    def __init__(
        self,
        bus: EventBus,
        path: str | Path,
        *,
        kinds: Collection[str] = TRACE_KINDS,
        report: Report | None = None,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.path = Path(path)
        try:
            raw = open(self.path, "w", encoding="utf-8", buffering=BUFFER)  # noqa: SIM115
        except OSError as exc:
            raise ConfigError(f"--trace {path}: cannot write it ({exc.strerror})") from None
        self._file: io.TextIOWrapper | None = raw
        self._report = report or (lambda text: None)
        self._wall = wall
        self.written = 0
        self.failed: str | None = None  # why tracing stopped, once it did
        self._sub: Subscription | None = bus.subscribe(kinds, maxlen=QUEUE, notify=self._drain)

    @property
    def dropped(self) -> int:
        return self._sub.dropped if self._sub is not None else 0

    def _drain(self) -> None:
        sub, out = self._sub, self._file
        if sub is None or out is None:
            return
        wall = repr(round(self._wall(), 6))
        try:
            for event in sub.take():
                out.write(line(event, wall) + "\n")
                self.written += 1
        except (OSError, ValueError) as exc:  # a full disk; a file closed under us
            self._fail(f"trace {self.path}: {getattr(exc, 'strerror', None) or exc}")

    def _fail(self, why: str) -> None:
        self.failed = why
        self._report(f"{why}: tracing stopped, the plant keeps running")
        self._stop()

    def _stop(self) -> None:
        if self._sub is not None:
            self._sub.close()
            self._sub = None
        out, self._file = self._file, None
        if out is not None:
            try:
                out.close()
            except (OSError, ValueError) as exc:
                if self.failed is None:
                    self.failed = f"trace {self.path}: {exc}"
                    self._report(f"{self.failed}: the end of the trace is lost")

    def close(self) -> None:
        """Write what is left, flush and close (idempotent)."""
        if self._sub is not None:
            self._drain()
        self._stop()


# --- reading a trace back -------------------------------------------------------------


def read_records(path: str | Path) -> list[dict[str, object]]:
    """Every record of a trace file; ConfigError naming the line that is not one."""
    try:
        text = Path(path).read_text("utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read it ({exc.strerror})") from None
    records: list[dict[str, object]] = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            item = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"{path} line {number}: not a trace line ({exc.msg})") from None
        if not isinstance(item, dict) or "t" not in item or "kind" not in item:
            raise ConfigError(f"{path} line {number}: not a trace line (needs t and kind)")
        records.append(item)
    return records


def describe(item: Mapping[str, object]) -> str:
    """One line for people: time, endpoint, direction, slave, function, address/count, result."""
    head = f"{float(str(item.get('t', 0))):11.6f} s  {item.get('endpoint', item.get('device'))}"
    direction = str(item.get("dir", "?"))
    if item.get("kind") == "serial":
        text = str(item.get("text", ""))
        return (
            f"{head} ch {item.get('channel')}  {direction:<3}  {item.get('count')} chars {text!r}"
        )
    if item.get("kind") != "modbus":
        return f"{head}  {item.get('kind')}"
    if "fault" in item:
        return _fault(head, direction, item)
    if "error" in item:
        return f"{head}  {direction:<3}  {item['error']}"
    slave = item.get("slave")
    parts = [head, f"{direction:<3}", f"slave {slave}", str(item.get("function_name", "?"))]
    if "address" in item:
        parts.append(f"addr {item['address']} count {item.get('count')}")
    if item.get("function") not in _PLAIN:  # never to be read as another (FC 22 is not 16)
        parts.append(_code(item))
    parts.append(_result(item))
    return "  ".join(p for p in parts if p)


# functions the TES executes (TES 7.1.1): their names alone; any other shows its code
_PLAIN = frozenset((1, 2, 3, 4, 5, 6, 7, 8, 15, 16))


def _code(item: Mapping[str, object]) -> str:
    """``[FC 22 = 0x16]``: the function code in decimal and hex, after its Modbus name."""
    code = item.get("function")
    return f"[FC {code} = 0x{code:02x}]" if isinstance(code, int) else ""


def _fault(head: str, direction: str, item: Mapping[str, object]) -> str:
    """``line fault crc_errors x1 (bad_crc): 01 03 00 05 00 01 95 ca``; a note after it."""
    text = f"{head}  {direction:<3}  line fault {item['fault']} x{item.get('fault_count', 1)}"
    reason, data = item.get("reason"), item.get("hex")
    if reason:
        text += f" ({reason})"
    if isinstance(data, str) and data:
        text += ": " + " ".join(data[i : i + 2] for i in range(0, min(len(data), 64), 2))
        text += " ..." if len(data) > 64 else ""
    if item.get("note"):
        text += f"  [{item['note']}]"
    return text


def _result(item: Mapping[str, object]) -> str:
    if item.get("crc") == "bad":
        return "CRC bad"
    if item.get("dir") == "out":
        exception = item.get("exception")
        who = f"from {item.get('from')}"
        return f"{who}: exception {exception}" if exception is not None else f"{who}: ok"
    if "rejected" in item:
        return f"rejected: exception {item['rejected']} ({item.get('reason')})"
    outcomes = item.get("tes")
    if not isinstance(outcomes, Mapping):
        return ""
    return "; ".join(f"{name} {state}" for name, state in outcomes.items())


def matches(
    item: Mapping[str, object],
    endpoint: str | None = None,
    slave: int | None = None,
    function: int | None = None,
) -> bool:
    """Whether a record passes the ``trace show`` filters."""
    if endpoint is not None and endpoint not in (item.get("endpoint"), item.get("device")):
        return False
    if slave is not None and item.get("slave") != slave:
        return False
    return function is None or item.get("function") == function


__all__ = [
    "TRACE_KINDS",
    "TraceWriter",
    "describe",
    "matches",
    "read_records",
    "record",
]
