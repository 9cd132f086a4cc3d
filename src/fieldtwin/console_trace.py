"""The console's ``trace`` command: the live traffic of the plant it runs on.

``trace on [modbus] [serial]`` subscribes to the plant's event bus; from then
on the output of every ``advance`` is followed by the frames and character
blocks that went over the wire during it.  ``trace show`` prints what is
waiting (what arrived since the last advance or show), ``trace off`` unsubscribes,
``trace`` alone says whether it is on.  The subscription is bounded: what a
slow reader misses is counted and said (docs/console.md, docs/trace.md).
"""

from __future__ import annotations

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import EventBus, Subscription
from fieldtwin.runtime.trace import TRACE_KINDS, describe, record

CONSOLE_QUEUE = 1000  # events the console holds between two commands
USAGE = "trace on [modbus] [serial] | trace off | trace show | trace"


class ConsoleTrace:
    """One console's subscription to the traffic of its plant."""

    def __init__(self, bus: EventBus) -> None:
        self._bus = bus
        self._sub: Subscription | None = None
        self._reported_drops = 0

    @property
    def on(self) -> bool:
        return self._sub is not None

    def command(self, args: list[str]) -> list[str]:
        if not args:
            return [self._state()]
        verb, rest = args[0].lower(), [a.lower() for a in args[1:]]
        if verb == "on":
            return self._on(rest)
        if verb in ("off", "show") and rest:
            raise ConfigError(f"trace {verb}: takes nothing more (usage: {USAGE})")
        if verb == "off":
            if self._sub is not None:
                self._sub.close()
                self._sub = None
            return ["trace off"]
        if verb == "show":
            if self._sub is None:
                raise ConfigError("trace show: the trace is off (trace on first)")
            return self.pending()
        raise ConfigError(f"trace: unknown {args[0]!r} (usage: {USAGE})")

    def _on(self, kinds: list[str]) -> list[str]:
        unknown = [k for k in kinds if k not in TRACE_KINDS]
        if unknown:
            raise ConfigError(f"trace on: unknown kind {unknown[0]!r} (allowed: modbus, serial)")
        wanted = tuple(k for k in TRACE_KINDS if k in kinds) or TRACE_KINDS
        if self._sub is not None:
            self._sub.close()
        self._sub = self._bus.subscribe(wanted, maxlen=CONSOLE_QUEUE)
        self._reported_drops = 0
        return [f"trace on ({', '.join(wanted)})"]

    def _state(self) -> str:
        sub = self._sub
        if sub is None:
            return "trace off"
        kinds = ", ".join(sorted(sub.kinds or TRACE_KINDS))
        return f"trace on ({kinds}): {len(sub)} waiting, {sub.dropped} dropped"

    def pending(self) -> list[str]:
        """What arrived since the last look, one line each (empty when off)."""
        sub = self._sub
        if sub is None:
            return []
        lines = [describe(record(event, 0.0)) for event in sub.take(CONSOLE_QUEUE)]
        if sub.dropped > self._reported_drops:
            lines.append(f"trace: {sub.dropped - self._reported_drops} events dropped")
            self._reported_drops = sub.dropped
        return lines


__all__ = ["ConsoleTrace"]
