"""Trends: a bounded ring of values per series, kept beside the observers (docs/dashboard.md).

A series is a tag of the plant file or any object the plant's PLC reads (``W4``,
``IW5,2,0``): every tag and every ``[dashboard] trends`` series is kept from the
start, a series asked for later (``GET /trends/{series}``) from then on, at most
:data:`MAX_SERIES` in all.  ``sample(now)`` is called on the runner's tick, where
the observers look at the plant (fieldtwin.session): at most every
:data:`SAMPLE_US` of simulated time it reads each series through the Device face
and the PLC's object reads (peeks: no side effect) and appends ``(t_s, value)`` to
its ring of :data:`MAX_POINTS`.  The rings are read from the web server's thread
under a lock: a page that opens late gets the history (``?since=``) without a hop
onto the simulation.
"""

from __future__ import annotations

import threading
from collections import deque
from typing import TYPE_CHECKING

from fieldtwin.clock import S
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant.tags import Tag, TagNumber, resolve, tag_value

if TYPE_CHECKING:
    from fieldtwin.plant import Plant

SAMPLE_US = 500_000  # the shortest simulated time between two samples of a series
MAX_POINTS = 1200  # points kept per series (10 minutes at one sample every 0.5 s)
MAX_SERIES = 64  # series kept beyond the plant's tags

Point = tuple[float, TagNumber | None]


class TooManySeries(FieldtwinError):
    """More series asked for than are kept."""


class Trends:
    """The rings of the series of one plant."""

    def __init__(
        self, plant: Plant, sample_us: int = SAMPLE_US, max_points: int = MAX_POINTS
    ) -> None:
        self.plant = plant
        self.sample_us = sample_us
        self.max_points = max_points
        self._lock = threading.Lock()
        self._series: dict[str, Tag] = {}  # by lower-case name (sim thread writes)
        self._rings: dict[str, deque[Point]] = {}
        self._next_us: int | None = None
        self._extra = 0
        for tag in plant.tags:
            self._add(tag)
        for name in plant.tags.trends:
            self.track(name)

    def _add(self, tag: Tag) -> None:
        key = tag.name.lower()
        if key in self._series:
            return
        with self._lock:
            self._series[key] = tag
            self._rings[key] = deque(maxlen=self.max_points)

    def track(self, name: str) -> Tag:
        """On the simulation's thread: the series ``name`` (a tag or an object), kept from
        now on; UnknownTag naming what is allowed, TooManySeries past the bound."""
        tag = resolve(self.plant, name)
        key = tag.name.lower()
        if key not in self._series:
            if self._extra >= MAX_SERIES:
                raise TooManySeries(
                    f"trends: {MAX_SERIES} series are kept beside the tags already"
                    " (allowed: a tag, or one of the series kept: GET /trends)"
                )
            self._extra += 1
            self._add(tag)
        return tag

    def tag(self, name: str) -> Tag | None:
        """The series ``name`` if it is kept (any thread)."""
        key = name.strip().lower()
        with self._lock:
            found = self._series.get(key)
            if found is None:  # an object by its source's spelling: "IW5,3" of a tag
                found = next((t for t in self._series.values() if t.source.name == name), None)
        return found

    def names(self) -> list[str]:
        with self._lock:
            return [t.name for t in self._series.values()]

    def sample(self, now: int, *, force: bool = False) -> None:
        """On the simulation's thread (the runner's tick): one point per series, at most
        every ``sample_us`` of simulated time."""
        if not force and self._next_us is not None and now < self._next_us:
            return
        self._next_us = now + self.sample_us
        t_s = now / S
        values: list[tuple[str, TagNumber | None]] = []
        for key, tag in list(self._series.items()):
            try:
                value = tag_value(self.plant, tag).value
            except FieldtwinError:  # a module out of its slot
                value = None
            values.append((key, value))
        with self._lock:
            for key, value in values:
                ring = self._rings[key]
                if ring and ring[-1][0] == t_s:
                    ring.pop()
                ring.append((t_s, value))

    def points(self, tag: Tag, since_s: float | None = None) -> list[Point]:
        """The points of ``tag``'s series after ``since_s`` (all kept when None)."""
        with self._lock:
            ring = self._rings.get(tag.name.lower())
            points = list(ring) if ring is not None else []
        if since_s is None:
            return points
        return [p for p in points if p[0] > since_s]


def tags_panel(plant: Plant) -> dict[str, object]:
    """What the dashboard shows of the tags: each tag's value now (``tags``), the default
    trends (``trend_defaults``) and, for a default trend that is an object without a
    tag, its value too (in ``tags``, with ``"object": true``)."""
    out: list[dict[str, object]] = []
    for tag in plant.tags:
        out.append(_json(plant, tag))
    for name in plant.tags.trends:
        if plant.tags.get(name) is None:
            try:
                out.append({**_json(plant, resolve(plant, name)), "object": True})
            except FieldtwinError:
                continue
    return {"tags": out, "trend_defaults": list(plant.tags.trends)}


def _json(plant: Plant, tag: Tag) -> dict[str, object]:
    try:
        return tag_value(plant, tag).json()
    except FieldtwinError:  # a module out of its slot
        return {
            "name": tag.name,
            "source_text": tag.source.text,
            "unit": tag.unit,
            "description": tag.description,
            "value": None,
            "raw": None,
            "text": "-",
        }


__all__ = ["MAX_POINTS", "MAX_SERIES", "SAMPLE_US", "TooManySeries", "Trends", "tags_panel"]
