"""A recording file read back as untrusted input (docs/record.md, "Bounds").

A recording can come from anywhere (a bug report, a download), so nothing in it
is trusted: it is read as a stream, one line at a time, and every bound below is
checked before anything is built from it.

* the file is a regular file, a gzip stream; what it inflates to is bounded by
  its size: past ``FREE_BYTES``, at most ``MAX_RATIO`` bytes of text per byte of
  the compressed file read so far (a fieldtwin recording compresses 5 to 20
  times; a gzip bomb a thousand times, and is refused after a few MiB);
* every line is at most ``MAX_LINE_BYTES`` (the header ``MAX_HEADER_BYTES``):
  a longer line is refused once that many bytes are read, the rest never is;
* JSON nesting at most ``MAX_DEPTH``, counted before the line is parsed (no
  parser recursion on ``[[[[...``); integers of at most 4300 digits (Python's own
  bound: a longer one is "not JSON");
* every record has the fields of its kind, of their types (``RECORD_FORMS``);
* times are whole microseconds from 0 to ``MAX_SIM_US`` (7 days of simulated
  time), never going back from one record to the next (in a replay's two streams,
  from one input to the next and from one output to the next); an input's
  ``fired`` count never goes back either; nothing follows the ``end`` record;
* the header has the fields ``HEADER_FIELDS`` and no other (an unknown field is
  refused by name: a newer fieldtwin's recording is not half understood), the
  plant text and each embedded file bounded, file names plain, file contents
  bytes (latin-1).

Every refusal is a ConfigError ``FILE: line N: what is wrong (what is allowed)``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from pathlib import PurePosixPath
from typing import Any

from fieldtwin.errors import ConfigError

MiB = 1024 * 1024
MAX_LINE_BYTES = 1 * MiB  # one record
MAX_HEADER_BYTES = 16 * MiB  # the header line: the plant text and the files it names
FREE_BYTES = 16 * MiB  # inflated text allowed whatever the ratio
MAX_RATIO = 100  # past FREE_BYTES: inflated bytes per compressed byte read
RATIO_EVERY = 1 * MiB  # the ratio is checked this often (inflated bytes)
MAX_DEPTH = 64  # JSON nesting of one line ([record, [call arguments, {...}]])
MAX_SIM_US = 7 * 24 * 3600 * 1_000_000  # simulated time a recording may span: 7 days
MAX_FIRED = 1 << 53  # clock events before an input
MAX_FILES = 256  # files one header embeds
MAX_FILE_CHARS = 4 * MiB  # one embedded file (bytes, as latin-1 text): a plant file's bound
MAX_PLANT_CHARS = 4 * MiB  # the plant file's text
MAX_NAME = 4096  # a file name the plant gives, a plant name
MAX_SPEED = 1e6
MAX_BAUD = 4_000_000  # the fastest rate termios names
SAMPLE_MS_RANGE = (10, 3_600_000)

FORMAT = "fieldtwin-recording"
VERSION = 1
# the header's fields, each with its check (add a field here: one line); anything else
# in a header is refused by name
HEADER_FIELDS = ("format", "version", "fieldtwin", "plant", "speed", "sample_ms", "console")
# How the recorded console lines ran (docs/record.md): "inline", a Python session's
# Console (an advance runs there and then); "modes", the control API's console of
# `fieldtwin run` (an advance or power break starts a runner mode).  A header
# without the field (recordings made before it) is "inline".
CONSOLES = ("inline", "modes")
PLANT_FIELDS = ("name", "text", "files")

Record = list[Any]
INPUT_KINDS = frozenset({"bind", "accept", "data", "close", "call", "line", "ret", "settings"})
OUTPUT_KINDS = frozenset({"send", "result", "object", "led", "chars", "dem"})

JSON_MARKS = re.compile(rb'"(?:[^"\\]|\\.)*"|[\[\]{}]')
_HEX = re.compile(r"(?:[0-9a-fA-F]{2})*")


class RecordingError(ConfigError):
    """A recording refused: damaged, out of bounds, or not one."""


# ------------------------------------------------------------------------- the fields


def is_int(value: object) -> bool:
    return type(value) is int


def _text(limit: int = MAX_LINE_BYTES) -> Callable[[object], bool]:
    return lambda value: isinstance(value, str) and len(value) <= limit


def _key(value: object) -> bool:  # t3, l1: a transport or listener name
    return isinstance(value, str) and 0 < len(value) <= 32


def _hex(value: object) -> bool:
    return isinstance(value, str) and _HEX.fullmatch(value) is not None


def _groups(value: object) -> bool:
    return (
        isinstance(value, list)
        and len(value) <= 16
        and all(isinstance(g, str) and len(g) <= 64 for g in value)
    )


def _anything(value: object) -> bool:
    return True


def _list(value: object) -> bool:
    return isinstance(value, list)


def _channel(value: object) -> bool:
    return value is None or is_int(value)


def _direction(value: object) -> bool:
    return value is None or (isinstance(value, str) and len(value) <= 16)


def _bool(value: object) -> bool:
    return isinstance(value, bool)


def _baud(value: object) -> bool:  # null: a rate termios has no constant for
    return value is None or (is_int(value) and 0 < value <= MAX_BAUD)  # type: ignore[operator]


def _stop_bits(value: object) -> bool:
    return value in (1, 2) and is_int(value)


Field = tuple[str, str, Callable[[object], bool]]  # name, what it must be, check

_NAME: Field = ("name", "a string of at most 64 characters", _text(64))
_TRANSPORT: Field = ("transport", "a transport name (t1, t2...)", _key)
_BYTES: Field = ("bytes", "hexadecimal bytes (an even count of 0-9 a-f)", _hex)
_DEVICE: Field = ("device", "a device address (a string)", _text(256))

# kind -> (an input: [kind, t, fired, ...] / an output: [kind, t, ...], the fields after)
RECORD_FORMS: dict[str, tuple[bool, tuple[Field, ...]]] = {
    "bind": (True, (("groups", "a list of port groups", _groups),)),
    "accept": (True, (("listener", "a listener name (l1, l2...)", _key),)),
    "data": (True, (_TRANSPORT, _BYTES)),
    "close": (True, (_TRANSPORT,)),
    "call": (
        True,
        (("command", "a control command name", _text(64)), ("arguments", "a list", _list)),
    ),
    "line": (True, (("line", "a console line (a string)", _text()),)),
    "ret": (True, ()),
    # the master's line settings on a pty changed (issue 23; older recordings have none)
    "settings": (
        True,
        (
            _TRANSPORT,
            ("baud", "a baud rate (1 to 4000000) or null", _baud),
            ("stop_bits", "1 or 2", _stop_bits),
            ("odd", "true or false (odd parity)", _bool),
        ),
    ),
    "end": (True, ()),
    "send": (False, (_TRANSPORT, _BYTES)),
    "result": (False, (("command", "a command name", _text(64)), ("answer", "JSON", _anything))),
    "object": (
        False,
        (_DEVICE, ("object", "an object name", _text(256)), ("value", "JSON", _anything)),
    ),
    "led": (
        False,
        (_DEVICE, ("led", "a LED name", _text(64)), ("state", "a LED state", _text(64))),
    ),
    "chars": (
        False,
        (
            _DEVICE,
            ("channel", "a channel number or null", _channel),
            ("direction", "in, out or null", _direction),
            _BYTES,
        ),
    ),
}
_DEM_CHANGE: tuple[Field, ...] = (
    _DEVICE,
    ("stamp", "a time stamp (a string)", _text(64)),
    ("type", "a message type (a string)", _text(32)),
    ("channel", "JSON", _anything),
    ("state", "JSON", _anything),
    ("stored", "true or false", _bool),
)
_DEM_OTHER = (*_DEM_CHANGE[:3], ("words", "JSON", _anything), _DEM_CHANGE[5])


_FORMS: dict[str, tuple[bool, tuple[Field, ...], int]] = {
    kind: (is_input, fields, 3 if is_input else 2)
    for kind, (is_input, fields) in {**RECORD_FORMS, "dem": (False, _DEM_CHANGE)}.items()
}
_DEM_OTHER_FORM = (False, _DEM_OTHER, 2)
KNOWN_KINDS = frozenset(_FORMS)
decode_json = json.JSONDecoder().decode


def _form(kind: str, is_input: bool, fields: tuple[Field, ...]) -> str:
    names = ["t_us", *(["fired"] if is_input else []), *(f[0] for f in fields)]
    return json.dumps(kind) + ", " + ", ".join(names)


class Checker:
    """Checks the records of one file in order: their form, their times (see above)."""

    def __init__(self, where: str) -> None:
        self.where = where
        self.t_us = 0  # the last record's time
        self.fired = 0  # the last input's clock events
        self.ended = False

    def fail(self, number: int, text: str) -> RecordingError:
        return RecordingError(f"{self.where}: line {number}: {text}")

    def check(self, item: object, number: int) -> Record:
        if type(item) is not list or not item or type(item[0]) is not str:
            raise self.fail(number, 'not a record (a JSON array ["kind", t_us, ...])')
        kind = item[0]
        if self.ended:
            raise self.fail(number, f"a {kind[:32]!r} record after the end record")
        form = _FORMS.get(kind)
        if form is None:
            raise self.fail(number, f"unknown record {kind[:32]!r}")
        if kind == "dem" and len(item) > 4 and item[4] != "change":
            form = _DEM_OTHER_FORM
        is_input, fields, head = form
        if len(item) != head + len(fields):
            raise self.fail(
                number,
                f"a {kind!r} record has {head + len(fields)} fields"
                f" [{_form(kind, is_input, fields)}], not {len(item)}",
            )
        t_us = item[1]
        if type(t_us) is not int or not 0 <= t_us <= MAX_SIM_US:
            raise self.fail(
                number,
                f"time {_short(t_us)} is not a whole number of microseconds from 0 to"
                f" {MAX_SIM_US} (7 days of simulated time)",
            )
        # a record's time is a stamp, not the instant it was written: an input's is when
        # its bytes arrived, a character block's when it began, which may fall before an
        # output of a later instant already written; inputs are ordered by their clock
        # events (``fired``, below), and every time is bounded (above)
        self.t_us = max(self.t_us, t_us)
        if is_input:
            fired = item[2]
            if type(fired) is not int or not 0 <= fired <= MAX_FIRED:
                raise self.fail(number, f"fired {_short(fired)} is not a count of clock events")
            if fired < self.fired:
                raise self.fail(
                    number,
                    f"fired {fired} is less than the previous input's ({self.fired}):"
                    " clock events never run backwards",
                )
            self.fired = fired
        index = head
        for name, what, ok in fields:
            value = item[index]
            if not ok(value):
                raise self.fail(number, f"a {kind!r} record's {name} {_short(value)} is not {what}")
            index += 1
        if kind == "end":
            self.ended = True
        return item


def _short(value: object) -> str:
    text = json.dumps(value) if is_int(value) or isinstance(value, str | None) else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


# ------------------------------------------------------------------------- the header


def check_header(data: object, where: str) -> dict[str, Any]:
    """The header's fields, checked (see the module docstring)."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise RecordingError(f"{where}: not a fieldtwin recording (no {FORMAT} header)")
    version = data.get("version")
    if version != VERSION:
        raise RecordingError(
            f"{where}: recording format version {_short(version)}; this fieldtwin reads"
            f" version {VERSION}"
        )
    unknown = sorted(str(k)[:40] for k in data if k not in HEADER_FIELDS)
    if unknown:
        raise RecordingError(
            f"{where}: line 1: unknown header field(s) {', '.join(map(repr, unknown))}"
            f" (a version {VERSION} header has {', '.join(HEADER_FIELDS)})"
        )

    def damaged(field: str, allowed: str) -> RecordingError:
        return RecordingError(f"{where}: line 1: the header is damaged: {field} must be {allowed}")

    plant = data.get("plant")
    if not isinstance(plant, dict) or sorted(plant) != sorted(PLANT_FIELDS):
        raise damaged("plant", f"an object with {', '.join(PLANT_FIELDS)}")
    name, text, files = plant["name"], plant["text"], plant["files"]
    if not isinstance(name, str) or len(name) > MAX_NAME or "\0" in name:
        raise damaged("plant.name", f"a file name of at most {MAX_NAME} characters")
    if not isinstance(text, str) or len(text) > MAX_PLANT_CHARS:
        raise damaged("plant.text", f"the plant file's text, at most {MAX_PLANT_CHARS} characters")
    if not isinstance(files, dict) or len(files) > MAX_FILES:
        raise damaged("plant.files", f"an object of at most {MAX_FILES} files")
    for file_name, content in files.items():
        shown = _short(file_name)
        if not file_name or len(file_name) > MAX_NAME or "\0" in file_name:
            raise damaged(f"plant.files {shown}", "a file name (no NUL)")
        if len(PurePosixPath(file_name).name.encode("utf-8", "replace")) > 200:
            raise damaged(f"plant.files {shown}", "a file name of at most 200 bytes")
        if not isinstance(content, str) or len(content) > MAX_FILE_CHARS:
            raise damaged(f"plant.files {shown}", f"a file's bytes, at most {MAX_FILE_CHARS}")
        if content and max(content) > "\xff":
            raise damaged(f"plant.files {shown}", "a file's bytes (latin-1 text)")
    speed = data.get("speed")
    if speed is not None and (
        isinstance(speed, bool)
        or not isinstance(speed, int | float)
        or not math.isfinite(speed)
        or not 0 < speed <= MAX_SPEED
    ):
        raise damaged("speed", f"null (as fast as possible) or a factor > 0 and <= {MAX_SPEED:g}")
    sample = data.get("sample_ms")
    low, high = SAMPLE_MS_RANGE
    if not isinstance(sample, int) or isinstance(sample, bool) or not low <= sample <= high:
        raise damaged("sample_ms", f"a whole number of ms from {low} to {high}")
    made_by = data.get("fieldtwin", "?")
    if not isinstance(made_by, str) or len(made_by) > 64:
        raise damaged("fieldtwin", "a version (a string)")
    console = data.get("console", "inline")
    if console not in CONSOLES:
        raise damaged("console", " or ".join(map(repr, CONSOLES)))
    return {**data, "fieldtwin": made_by, "console": console}


__all__ = [
    "FORMAT",
    "HEADER_FIELDS",
    "MAX_DEPTH",
    "MAX_HEADER_BYTES",
    "MAX_LINE_BYTES",
    "MAX_RATIO",
    "MAX_SIM_US",
    "VERSION",
    "Checker",
    "RecordingError",
    "check_header",
]
