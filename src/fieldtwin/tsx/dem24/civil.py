"""Civil dates for the module clock, written here (no datetime in a sans-IO core).

The time table of DEM 4.1-1 carries a two-digit year (0..99); the module only needs
leap years to count days, and in 1970..2069 a year is leap when it is divisible by 4
(2000 is).  Years 70..99 are 1970..1999 and 0..69 are 2000..2069 (docs/manual-notes.md).
Module time is a count of milliseconds since 1970-01-01 00:00:00.000.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import NamedTuple

from fieldtwin.errors import ConfigError

MS_PER_DAY = 86_400_000
_DAYS = (31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31)


def full_year(yy: int) -> int:
    """The two-digit year of the time table -> the civil year (pivot at 70)."""
    return 1900 + yy if yy >= 70 else 2000 + yy


def is_leap(year: int) -> bool:
    return year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)


def days_in_month(year: int, month: int) -> int:
    return 29 if month == 2 and is_leap(year) else _DAYS[month - 1]


def days_from_civil(year: int, month: int, day: int) -> int:
    """Days since 1970-01-01 (the proleptic Gregorian calendar, H. Hinnant's method)."""
    y = year - (month <= 2)
    era = y // 400
    yoe = y - era * 400
    doy = (153 * (month + (-3 if month > 2 else 9)) + 2) // 5 + day - 1
    doe = yoe * 365 + yoe // 4 - yoe // 100 + doy
    return era * 146097 + doe - 719468


@lru_cache(maxsize=64)  # a pure function, asked at every message for the same few days
def civil_from_days(days: int) -> tuple[int, int, int]:
    """Days since 1970-01-01 -> (year, month, day)."""
    z = days + 719468
    era = z // 146097
    doe = z - era * 146097
    yoe = (doe - doe // 1460 + doe // 36524 - doe // 146096) // 365
    doy = doe - (365 * yoe + yoe // 4 - yoe // 100)
    mp = (5 * doy + 2) // 153
    day = doy - (153 * mp + 2) // 5 + 1
    month = mp + (3 if mp < 10 else -9)
    return yoe + era * 400 + (month <= 2), month, day


class CivilTime(NamedTuple):
    """A date and time to the millisecond, as the messages of DEM 4.2-2 carry it.

    A named tuple, not a frozen dataclass: one is made for every message logged, and a
    frozen dataclass costs three times as much to make (docs/decisions.md)."""

    year: int  # full civil year
    month: int
    day: int
    hour: int
    minute: int
    second: int
    ms: int = 0

    @property
    def yy(self) -> int:
        return self.year % 100

    def to_ms(self) -> int:
        days = days_from_civil(self.year, self.month, self.day)
        return ((days * 24 + self.hour) * 60 + self.minute) * 60_000 + self.second * 1000 + self.ms

    @staticmethod
    def from_ms(value: int) -> CivilTime:
        minutes, rest = divmod(value, 60_000)
        # (year, month, day, hour, minute) + (second, ms), made as a tuple in C
        return _new_civil(CivilTime, minute_fields(minutes) + divmod(rest, 1000))

    def __str__(self) -> str:
        return (
            f"{self.year:04d}-{self.month:02d}-{self.day:02d}"
            f" {self.hour:02d}:{self.minute:02d}:{self.second:02d}.{self.ms:03d}"
        )


_new_civil = tuple.__new__  # CivilTime(*fields) without the Python-level __new__


@lru_cache(maxsize=64)  # once per minute of module time that messages are stamped in
def minute_fields(minutes: int) -> tuple[int, int, int, int, int]:
    """Minutes since 1970-01-01 00:00 -> (year, month, day, hour, minute)."""
    days, rest = divmod(minutes, 1440)
    hour, minute = divmod(rest, 60)
    return (*civil_from_days(days), hour, minute)


def valid_fields(yy: int, month: int, day: int, hour: int, minute: int, second: int) -> bool:
    """DEM 4.1-1 ranges: year 0..99, month 1..12, day 1..31 (of that month), 0..23, 0..59."""
    if not (0 <= yy <= 99 and 1 <= month <= 12 and 0 <= hour <= 23):
        return False
    if not (0 <= minute <= 59 and 0 <= second <= 59):
        return False
    return 1 <= day <= days_in_month(full_year(yy), month)


_ISO_RE = re.compile(r"^(\d{4})-(\d{2})-(\d{2})[T ](\d{2}):(\d{2}):(\d{2})$")


def parse_iso(text: str, where: str) -> CivilTime:
    """``1994-07-15T18:05:33`` -> CivilTime (years 1970..2069, the table's range)."""
    match = _ISO_RE.match(text.strip())
    if match is None:
        raise ConfigError(f"{where}: {text!r} is not a time (allowed YYYY-MM-DDTHH:MM:SS)")
    year, month, day, hour, minute, second = (int(g) for g in match.groups())
    if not 1970 <= year <= 2069 or not valid_fields(year % 100, month, day, hour, minute, second):
        raise ConfigError(
            f"{where}: {text!r} is not a valid date and time in 1970..2069"
            " (the module's table holds a two-digit year)"
        )
    return CivilTime(year, month, day, hour, minute, second)
