"""A recording file read as a stream of bounded lines (docs/record.md, "Bounds").

The bounds and the checks of what a line holds are fieldtwin.runtime.recfile's;
here the file is opened (a regular file only), inflated with its ratio to the
compressed bytes bounded, cut into lines of bounded length, each parsed with its
nesting bounded, and handed on with its line number.  Every refusal is a
ConfigError ``FILE: line N: what is wrong (what is allowed)``.
"""

from __future__ import annotations

import gzip
import json
import os
import stat
import zlib
from collections.abc import Collection, Generator, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, BinaryIO

from fieldtwin.runtime.recfile import (
    FORMAT,
    FREE_BYTES,
    JSON_MARKS,
    KNOWN_KINDS,
    MAX_DEPTH,
    MAX_HEADER_BYTES,
    MAX_LINE_BYTES,
    MAX_RATIO,
    MAX_SIM_US,
    RATIO_EVERY,
    Checker,
    MiB,
    Record,
    RecordingError,
    check_header,
    decode_json,
    is_int,
)


@contextmanager
def reading(where: str) -> Iterator[None]:
    """gzip, zlib and OS errors as a refusal naming the file."""
    try:
        yield
    except (OSError, zlib.error) as exc:  # gzip.BadGzipFile is an OSError
        text = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise RecordingError(f"{where}: cannot read the recording ({text})") from None
    except EOFError:
        raise RecordingError(f"{where}: the recording is cut short (not closed?)") from None


def _open(path: str | Path, where: str) -> BinaryIO:
    """The regular file ``path`` (a FIFO, a device, a directory refused unopened)."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    mode = os.stat(path).st_mode
    if not stat.S_ISREG(mode):
        raise RecordingError(f"{where}: not a regular file (a recording is a file)")
    fd = os.open(path, flags)
    file = os.fdopen(fd, "rb")
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        file.close()
        raise RecordingError(f"{where}: not a regular file (a recording is a file)")
    return file


def lines(path: str | Path) -> Generator[tuple[int, bytes], None, None]:
    """(line number, line) of the inflated file, each line bounded, the whole bounded by
    the compressed size read (see the module docstring).  Errors name the file and line."""
    where = str(path)
    with reading(where), _open(path, where) as raw, gzip.GzipFile(fileobj=raw) as file:
        inflated, check_at = 0, FREE_BYTES
        number = 0
        while True:
            number += 1
            limit = MAX_HEADER_BYTES if number == 1 else MAX_LINE_BYTES
            line = file.readline(limit + 1)
            if not line:
                return
            if len(line) > limit:
                raise RecordingError(
                    f"{where}: line {number}: longer than {limit // MiB} MiB"
                    f" (a {'header' if number == 1 else 'record'} is at most {limit // MiB} MiB)"
                )
            inflated += len(line)
            if inflated >= check_at:
                check_at = inflated + RATIO_EVERY
                if inflated > FREE_BYTES + MAX_RATIO * raw.tell():
                    raise RecordingError(
                        f"{where}: line {number}: inflates more than {MAX_RATIO} times past"
                        f" {FREE_BYTES // MiB} MiB (a gzip bomb, not a recording)"
                    )
            yield number, line


def parse(line: bytes, where: str, number: int) -> object:
    """One line's JSON, its nesting bounded before it is parsed."""
    if line.count(b"[") + line.count(b"{") > MAX_DEPTH:
        depth = 0
        for token in JSON_MARKS.finditer(line):
            mark = token.group()
            if mark in (b"[", b"{"):
                depth += 1
                if depth > MAX_DEPTH:
                    raise RecordingError(
                        f"{where}: line {number}: nested more than {MAX_DEPTH} deep"
                    )
            elif mark in (b"]", b"}"):
                depth -= 1
    try:
        return decode_json(line.decode("utf-8"))
    except (ValueError, RecursionError):  # JSONDecodeError, UnicodeDecodeError among them
        raise RecordingError(f"{where}: line {number}: not JSON (damaged recording)") from None


def header_data(path: str | Path) -> dict[str, Any]:
    """The checked header fields of the recording ``path``."""
    where = str(path)
    stream = lines(path)
    try:
        first = next(stream, None)
        if first is None:
            raise RecordingError(f"{where}: empty (no {FORMAT} header)")
        return check_header(parse(first[1], where, 1), where)
    finally:
        stream.close()


def extent(path: str | Path) -> int:
    """The time of the recording's last record (its end): a replay never runs past it.
    Only the last line is parsed; a damage is left to the streams that read it."""
    last = b""
    stream = lines(path)
    try:
        for number, line in stream:
            if number > 1:
                last = line
    finally:
        stream.close()
    try:
        item = json.loads(last) if last.count(b"[") <= MAX_DEPTH else None
    except (ValueError, RecursionError):
        item = None
    if isinstance(item, list) and len(item) > 1 and is_int(item[1]):
        return max(0, min(int(item[1]), MAX_SIM_US))
    return MAX_SIM_US


def records(
    path: str | Path, kinds: Collection[str] | None = None
) -> Generator[tuple[int, Record], None, None]:
    """(line number, record) after the header, every record checked.

    With ``kinds``, only the records of those kinds (and ``end``) are parsed and
    checked, the times in order among them: a replay reads the inputs and the outputs
    as two streams, each checking its half.  A line whose kind is not plain to see
    (``["data",...`` as fieldtwin writes it) is parsed and checked in every stream."""
    where = str(path)
    checker = Checker(where)
    wanted = None if kinds is None else frozenset(kinds) | {"end"}
    stream = lines(path)
    try:
        for number, line in stream:
            if number == 1:
                continue
            if wanted is not None and line[:2] == b'["':
                close = line.find(b'"', 2, 16)
                kind = line[2:close].decode("latin-1") if close > 0 else ""
                if kind in KNOWN_KINDS and kind not in wanted:
                    continue  # the other stream's to check
            record = checker.check(parse(line, where, number), number)
            if kinds is None or record[0] in kinds:
                yield number, record
    finally:
        stream.close()


__all__ = ["extent", "header_data", "lines", "parse", "reading", "records"]
