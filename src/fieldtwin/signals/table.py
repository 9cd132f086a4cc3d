"""A CSV file of (time in seconds, value) rows -> points of a piecewise-linear signal.

Comma-separated, one row per point; the first row may be a header (any row whose
time is not a number is taken as one, on line 1 only); blank lines and lines
starting with ``#`` are skipped.  Times must not decrease.

The file is read with fieldtwin.textfile's bounds (a regular file of at most
MAX_FILE_BYTES, UTF-8).  An error names the file, the line and the column at
fault and what is allowed, and never quotes the line: the file may be anything
its name points at (docs/signals.md).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from fieldtwin.clock import seconds
from fieldtwin.errors import ConfigError
from fieldtwin.textfile import MiB, read_text

_ROW_FORM = "allowed: 'time_s,value' with two numbers, times not decreasing"
MAX_FILE_BYTES = 16 * MiB  # a signal file is read whole: bounded (DESIGN rule 14)


def read_points(path: Path) -> list[tuple[int, float]]:
    """Rows of ``path`` as (t_us, value); ConfigError naming file and line on a bad row."""
    text = read_text(path, MAX_FILE_BYTES, "signal file")
    points: list[tuple[int, float]] = []
    for line_no, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [cell.strip() for cell in row]
        if not any(cells) or cells[0].startswith("#"):
            continue
        point = _parse_row(path, line_no, cells, header_allowed=line_no == 1)
        if point is None:
            continue
        if points and point[0] < points[-1][0]:
            raise ConfigError(
                f"{path}:{line_no}: the time is before the previous row's ({_ROW_FORM})"
            )
        points.append(point)
    if not points:
        raise ConfigError(f"{path}: no data rows ({_ROW_FORM})")
    return points


def _parse_row(
    path: Path, line_no: int, cells: list[str], *, header_allowed: bool
) -> tuple[int, float] | None:
    where = f"{path}:{line_no}"
    if len(cells) != 2:
        count = f"{len(cells)} column{'' if len(cells) == 1 else 's'}"
        raise ConfigError(f"{where}: {count}, not 2 ({_ROW_FORM})")
    time_s, value = _number(cells[0]), _number(cells[1])
    if time_s is None and header_allowed:
        return None  # a header row
    for number, column in ((time_s, "column 1 (time_s)"), (value, "column 2 (value)")):
        if number is None:
            raise ConfigError(f"{where}: {column} is not a finite number ({_ROW_FORM})")
    assert time_s is not None and value is not None
    if time_s < 0:
        raise ConfigError(f"{where}: the time is negative ({_ROW_FORM})")
    return seconds(time_s), value


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None
