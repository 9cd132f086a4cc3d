"""The characters of an SCM channel on the plant's event bus (re-exported by
fieldtwin.runtime.wiretap, where it was)."""

from __future__ import annotations

from collections.abc import Mapping

from fieldtwin.clock import SimClock
from fieldtwin.devices.chars import KIND_SERIAL, CharBlocks
from fieldtwin.runtime.events import EventBus


class CharTap(CharBlocks):
    """Publishes the characters of one SCM channel, in and out, in blocks, on ``bus``
    (fieldtwin.devices.chars: an SCM's own stream publishes the same way)."""

    def __init__(
        self, bus: EventBus, clock: SimClock, device: str, channel: int, line: str
    ) -> None:
        self.bus = bus
        self.device = device
        super().__init__(clock, channel, line, self._to_bus, lambda: bus.active)

    def _to_bus(self, start: int, fields: Mapping[str, object]) -> None:
        self.bus.publish(start, KIND_SERIAL, self.device, dict(fields))


__all__ = ["CharTap"]
