"""A recording's file: its header, the writer's thread, and reading it back (docs/record.md).

The simulation's thread only appends each record, raw (the bytes as bytes), to the
writer's bounded queue (``QUEUE`` records); the writer's thread turns them into JSON
(bytes into hex), compresses and writes them, in order.  A recording is an input log
and stays complete: when its writer falls behind and the queue is full, the plant
waits for it (the time waited is told when the recording closes; docs/record.md).
Reading checks every line as untrusted input (fieldtwin.runtime.recfile).
"""

from __future__ import annotations

import gzip
import json
import threading
import time
from collections import deque
from collections.abc import Collection, Generator, Mapping
from dataclasses import dataclass
from pathlib import Path

import orjson

from fieldtwin import __version__
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.recfile import (
    FORMAT,
    MAX_HEADER_BYTES,
    VERSION,
    MiB,
    Record,
    check_header,
)
from fieldtwin.runtime.recstream import header_data
from fieldtwin.runtime.recstream import records as numbered_records

QUEUE = 50_000  # records handed to the writer and not yet written: past it the plant waits
WRITE_BATCH = 2000  # records the writer's thread turns into one compressed write
WRITE_S = 0.01  # the writer's thread takes what was queued this often
# gzip's fastest level: a recording is written while the plant runs (level 6 cost the
# writer's thread three times the CPU for files about a quarter smaller)
COMPRESS = 1


@dataclass(frozen=True, slots=True)
class Header:
    """What a recording starts with."""

    plant_name: str
    plant_text: str
    files: Mapping[str, str]  # a name the plant file gives -> that file's text (latin-1)
    speed: float | None
    sample_ms: int
    version: int = VERSION
    fieldtwin: str = __version__
    console: str = "inline"  # how its console lines ran: one of recfile.CONSOLES

    def as_json(self) -> dict[str, object]:
        return {
            "format": FORMAT,
            "version": self.version,
            "fieldtwin": self.fieldtwin,
            "plant": {"name": self.plant_name, "text": self.plant_text, "files": dict(self.files)},
            "speed": self.speed,
            "sample_ms": self.sample_ms,
            "console": self.console,
        }

    @classmethod
    def from_json(cls, data: object, where: str) -> Header:
        """The header of a recording, every field checked (fieldtwin.runtime.recfile)."""
        fields = check_header(data, where)
        plant, speed = fields["plant"], fields["speed"]
        return cls(
            plant["name"],
            plant["text"],
            dict(plant["files"]),
            None if speed is None else float(speed),
            fields["sample_ms"],
            fields["version"],
            fields["fieldtwin"],
            fields["console"],
        )


class Keys:
    """Names of transports and listeners in the order they are attached (t1.., l1..)."""

    def __init__(self) -> None:
        self._links = 0
        self._listeners = 0

    def link(self) -> str:
        self._links += 1
        return f"t{self._links}"

    def listener(self) -> str:
        self._listeners += 1
        return f"l{self._listeners}"


class RecordWriter:
    """A gzip file of JSON lines: the header, then the records, written by a thread of
    its own from a bounded queue (``add`` waits when the queue is full)."""

    def __init__(self, path: str | Path, header: Header) -> None:
        self.path = Path(path)
        size = len(_line(header.as_json()))
        if size > MAX_HEADER_BYTES:  # a replay would refuse it: say so now
            raise ConfigError(
                f"--record {path}: the plant file and the files it names make a header of"
                f" {size / MiB:.1f} MiB; a recording's header is at most"
                f" {MAX_HEADER_BYTES // MiB} MiB (docs/record.md)"
            )
        try:
            self._file: gzip.GzipFile | None = gzip.GzipFile(
                self.path, "wb", compresslevel=COMPRESS
            )
        except OSError as exc:
            raise ConfigError(f"--record {path}: cannot write ({exc.strerror})") from None
        self.records = 0
        self.waited_s = 0.0  # how long the plant waited for the writer (a full queue)
        self.waits = 0
        self.failed: BaseException | None = None  # what stopped the writer's thread
        self._file.write(_line(header.as_json()))
        self._queue: deque[Record] = deque()
        self._room = threading.Condition()
        self._ending = False
        self._thread: threading.Thread | None = threading.Thread(
            target=self._write_all, name="fieldtwin-record", daemon=True
        )
        self._thread.start()

    def add(self, record: Record) -> None:
        """Hand one record to the writer (the simulation's thread): waits while the
        writer is ``QUEUE`` records behind."""
        if self._thread is None:
            return
        if self.failed is not None:
            raise self.failed
        pending = self._queue
        if len(pending) >= QUEUE:
            started = time.perf_counter()
            with self._room:
                while len(pending) >= QUEUE and self.failed is None:
                    self._room.wait(WRITE_S)
            self.waited_s += time.perf_counter() - started
            self.waits += 1
        self.records += 1
        pending.append(record)

    def _write_all(self) -> None:
        file, pending = self._file, self._queue
        assert file is not None
        while True:
            ending = self._ending
            if not ending:
                time.sleep(WRITE_S)  # a batch gathers: no wake-up per record
            while pending:
                count = min(WRITE_BATCH, len(pending))
                batch = [pending.popleft() for _ in range(count)]
                if self.failed is None:
                    try:
                        file.write(b"".join(_line(record) for record in batch))
                    except (OSError, ValueError) as exc:
                        self.failed = exc  # told on the next add() or on close()
                with self._room:
                    self._room.notify_all()
            if ending:
                return

    def close(self) -> None:
        """Write what is queued, then close the file (idempotent)."""
        thread, self._thread = self._thread, None
        if thread is not None:
            self._ending = True
            thread.join()
        if self._file is not None:
            file, self._file = self._file, None
            file.close()
        if self.failed is not None:
            failed, self.failed = self.failed, None
            raise failed


def _line(item: object) -> bytes:
    if type(item) is list and item and item[0] in _HOT and set(map(type, item)) <= _PLAIN:
        try:
            return _DUMPS(item, default=_plain, option=_NEWLINE)
        except (TypeError, orjson.JSONEncodeError):
            pass
    text = json.dumps(item, separators=(",", ":"), ensure_ascii=False, default=_plain)
    return text.encode("utf-8") + b"\n"


# The records of the wire, one per chunk in and out (``data``, ``send``: a kind, times,
# a key and bytes): written by orjson, as json writes them (strings, integers, the
# bytes as hex by ``_plain``), at a fraction of the cost; a float, which orjson may write
# differently, or anything else goes through json.
_HOT = frozenset(("data", "send"))
_PLAIN = frozenset((str, int, bytes))
_DUMPS = orjson.dumps
_NEWLINE = orjson.OPT_APPEND_NEWLINE


def _plain(value: object) -> object:
    """Bytes as hex (the simulation's thread hands them raw), anything else as text."""
    if isinstance(value, bytes | bytearray | memoryview):
        return bytes(value).hex()
    return str(value)


def read_recording(path: str | Path) -> tuple[Header, list[Record]]:
    """The header and the records of a recording, whole (a short one: tests, tools);
    errors name the file and the line."""
    return read_header(path), list(iter_records(path))


def read_header(path: str | Path) -> Header:
    return Header.from_json(header_data(path), str(path))


def iter_records(
    path: str | Path, kinds: Collection[str] | None = None
) -> Generator[Record, None, None]:
    """The records after the header, one at a time (of ``kinds`` only, when given): a
    recording of hours is never held in memory whole.  Every line is checked as
    untrusted input (fieldtwin.runtime.recfile): bounded, of its kind's form, in time
    order."""
    return (record for _, record in numbered_records(path, kinds))


__all__ = [
    "QUEUE",
    "Header",
    "Keys",
    "RecordWriter",
    "iter_records",
    "read_header",
    "read_recording",
]
