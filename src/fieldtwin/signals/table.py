"""A CSV file of (time in seconds, value) rows -> points of a piecewise-linear signal.

Comma-separated, one row per point; the first row may be a header (any row whose
time is not a number is taken as one, on line 1 only); blank lines and lines
starting with ``#`` are skipped.  Times must not decrease.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from fieldtwin.clock import seconds
from fieldtwin.errors import ConfigError

_ROW_FORM = "allowed: 'time_s,value' with two numbers, times not decreasing"
MAX_FILE_BYTES = 16 * 1024 * 1024  # a signal file is read whole: bounded (DESIGN rule 14)


def read_points(path: Path) -> list[tuple[int, float]]:
    """Rows of ``path`` as (t_us, value); ConfigError naming file and line on a bad row."""
    text = _read_bounded(path)
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
                f"{path}:{line_no}: time {cells[0]} s is before the previous row ({_ROW_FORM})"
            )
        points.append(point)
    if not points:
        raise ConfigError(f"{path}: no data rows ({_ROW_FORM})")
    return points


def _read_bounded(path: Path) -> str:
    """The file's text, at most MAX_FILE_BYTES (``/dev/zero`` or a device never ends)."""
    try:
        with path.open("rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the signal file ({exc.strerror})") from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(
            f"{path}: larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB"
            " (allowed: a CSV file of at most that size)"
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a UTF-8 text file ({_ROW_FORM})") from None


def _parse_row(
    path: Path, line_no: int, cells: list[str], *, header_allowed: bool
) -> tuple[int, float] | None:
    where = f"{path}:{line_no}"
    if len(cells) != 2:
        raise ConfigError(f"{where}: {len(cells)} columns in {','.join(cells)!r} ({_ROW_FORM})")
    time_s, value = _number(cells[0]), _number(cells[1])
    if time_s is None and header_allowed:
        return None  # a header row
    if time_s is None or value is None:
        raise ConfigError(f"{where}: {','.join(cells)!r} is not two numbers ({_ROW_FORM})")
    if time_s < 0:
        raise ConfigError(f"{where}: time {cells[0]} s is negative ({_ROW_FORM})")
    return seconds(time_s), value


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None
