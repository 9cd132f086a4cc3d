"""Characters of a raw line, in blocks: what a device publishes of its serial channels.

A channel sends one character at a time; characters in the same direction less
than BLOCK_GAP_US apart make one block, published when the line has been quiet
that long in that direction (a clock event of the blocker's own: it only
publishes), when the direction turns, or at MAX_BLOCK characters.  An SCM's
stream (fieldtwin.devices.scm) and the runtime's CharTap publish through this.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from fieldtwin.clock import MS, Handle, SimClock

KIND_SERIAL = "serial"  # the event kind of a channel's characters (docs/trace.md)
MAX_BLOCK = 1024  # characters of one block an event carries (the count says the rest)
BLOCK_GAP_US = 5 * MS  # a quieter line ends a block (about 4 characters at 9600 Bd)


class CharBlocks:
    """Collects the characters of one channel, in and out, and publishes them in blocks:
    ``publish(start_us, {"endpoint", "channel", "dir", "count", "hex", "text"})``."""

    def __init__(
        self,
        clock: SimClock,
        channel: int,
        line: str,
        publish: Callable[[int, Mapping[str, object]], None],
        active: Callable[[], bool] = lambda: True,
    ) -> None:
        self._clock = clock
        self.channel = channel
        self.line = line
        self._publish = publish
        self._active = active
        self._blocks: dict[str, tuple[int, int, bytearray]] = {}  # dir -> (start, last, chars)
        self._timers: dict[str, Handle] = {}

    @property
    def active(self) -> bool:
        """Whether anyone looks now (a line skips its characters otherwise)."""
        return self._active()

    def chars(self, direction: str, data: bytes, now: int | None = None) -> None:
        t_us = self._clock.now if now is None else now
        block = self._blocks.get(direction)
        if block is not None and (t_us - block[1] > BLOCK_GAP_US or len(block[2]) >= MAX_BLOCK):
            self.flush(direction)
            block = None
        if block is None:
            block = (t_us, t_us, bytearray())
        self._blocks[direction] = (block[0], t_us, block[2] + data)
        timer = self._timers.pop(direction, None)
        if timer is not None:
            timer.cancel()
        flush_at = max(t_us + BLOCK_GAP_US, self._clock.now)
        self._timers[direction] = self._clock.schedule(flush_at, self._flusher(direction))

    def _flusher(self, direction: str) -> Callable[[int], None]:
        return lambda now: self.flush(direction)

    def flush(self, direction: str) -> None:
        """Publish the block waiting in ``direction`` (if any)."""
        block = self._blocks.pop(direction, None)
        timer = self._timers.pop(direction, None)
        if timer is not None:
            timer.cancel()
        if block is None:
            return
        start, _, data = block
        fields: dict[str, object] = {
            "endpoint": self.line,
            "channel": self.channel,
            "dir": direction,
            "count": len(data),
            "hex": bytes(data[:MAX_BLOCK]).hex(),
            "text": bytes(data[:MAX_BLOCK]).decode("latin-1"),
        }
        if len(data) > MAX_BLOCK:
            fields["truncated"] = True
        self._publish(start, fields)

    def close(self) -> None:
        """Publish what waits, cancel the timers."""
        for direction in list(self._blocks):
            self.flush(direction)
