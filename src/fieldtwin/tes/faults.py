"""The faults a TES can be given, by name, and the state of its line faults.

One catalogue per model (built once per model): wiring faults of the TES
32ET-S inputs (``short_<i>``, ``open_<i>``, §4.1.5), line faults aimed at this
one TES whatever else shares its line (``no_answer``, ``late_answer``,
``bad_crc``, ``broken_character``, ``not_ready``) and ``power_off`` (24 V
removed, §1).  :class:`LineFaults` holds what the slave adapter and the RTU
line ask about; the :class:`fieldtwin.tes.model.Tes` applies the others.
"""

from __future__ import annotations

import functools
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Protocol

from fieldtwin.clock import MS
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.tes import state
from fieldtwin.tes.digital import DigitalInputs, Wiring
from fieldtwin.tes.models import TesModel

LATE_MAX_MS = 60_000  # our bound for a late answer (the TES's own delay stops at 2570 ms, §7.2.7)
COUNT_MAX = 1_000_000  # bound of a fault limited to the next N requests or frames
NOT_READY_WINDOW_MAX_MS = 100  # §6.2.3.2 / §6.4.13: the 32-bit buffers refresh every 100 ms

Param = int | float


@dataclass(frozen=True, slots=True)
class FaultSpec:
    """One fault a TES model accepts: its name, what it does, the parameters it takes."""

    name: str
    description: str
    params: tuple[str, ...] = ()


LINE_FAULTS = (
    FaultSpec("no_answer", "the TES hears nothing: requests are neither executed nor answered"),
    FaultSpec(
        "late_answer",
        f"every answer leaves ms = 1..{LATE_MAX_MS} ms later than the answer delay",
        ("ms",),
    ),
    FaultSpec(
        "bad_crc",
        "frames to this TES arrive with a CRC error (RTU lines: counted by every TES, no answer);"
        " count = N: the next N frames only",
        ("count",),
    ),
    FaultSpec(
        "broken_character",
        "frames to this TES arrive with a wrong character (RTU lines: counted, no answer);"
        " count = N: the next N frames only",
        ("count",),
    ),
    FaultSpec(
        "not_ready",
        "requests in the 32-bit area get exception 4 'slave not ready'; count = N: the next N"
        f" only; window_ms = 0..<{NOT_READY_WINDOW_MAX_MS}: during each 100 ms buffer refresh",
        ("count", "window_ms"),
    ),
    FaultSpec(
        "drop_connections",
        "every TCP connection this TES is reached through (tcp://, rtu+tcp://) is closed now;"
        " a one-shot: nothing stays in force, the master may connect again at once",
    ),
)
POWER_FAULT = FaultSpec("power_off", "24 V removed: no answer, RAM lost; cleared: power on (§1)")


@functools.cache
def fault_catalogue(model: TesModel) -> Mapping[str, FaultSpec]:
    """Every fault ``model`` accepts, by name."""
    specs: list[FaultSpec] = []
    if model.safety:  # §4.1.5 TES 32ET-S wiring supervision
        for i in range(model.digital_inputs):
            specs.append(FaultSpec(f"short_{i}", f"input {i}: short circuit (reads 1, §4.1.5)"))
            specs.append(FaultSpec(f"open_{i}", f"input {i}: broken wire (reads 0, §4.1.5)"))
    specs += [*LINE_FAULTS, POWER_FAULT]
    return MappingProxyType({s.name: s for s in specs})


def fault_spec(model: TesModel, name: str, params: Mapping[str, object]) -> FaultSpec:
    """The named fault, its parameters checked by name; ConfigError naming what is allowed."""
    catalogue = fault_catalogue(model)
    spec = catalogue.get(name)
    if spec is None:
        allowed = [n for n in catalogue if not n.startswith(("short_", "open_"))]
        if model.safety:
            last = model.digital_inputs - 1
            allowed = [f"short_0..short_{last}", f"open_0..open_{last}", *allowed]
        raise ConfigError(f"{model.name}: unknown fault {name!r} (allowed: {', '.join(allowed)})")
    unknown = sorted(set(params) - set(spec.params))
    if unknown:
        takes = ", ".join(spec.params) or "no parameters"
        raise ConfigError(f"{model.name}: fault {name!r} takes {takes}, not {', '.join(unknown)}")
    return spec


def number(name: str, value: object, lo: float, hi: float, unit: str = "") -> Param:
    """A checked numeric fault parameter."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
        raise ConfigError(
            f"fault parameter {name}: {value!r} not allowed (allowed {lo:g}..{hi:g}{unit})"
        )
    return value


class LineFaults:
    """The line faults of one TES, on whatever line or endpoint it is reached through."""

    def __init__(self) -> None:
        self.no_answer = False
        self.late_us = 0  # added to the answer delay
        self.corrupt: state.LineFault | None = None  # every frame, until cleared
        self._queued: dict[str, deque[state.LineFault]] = {"rs485": deque(), "rs232": deque()}
        self.not_ready_always = False
        self.not_ready_left = 0  # the next N requests in the 32-bit area
        self.not_ready_window_us = 0  # each 100 ms the TES refreshes its 32-bit buffers this long
        # who closes the TCP connections this TES is reached through (set by the endpoint
        # binder while it serves the TES; each returns how many it closed)
        self.droppers: list[Callable[[], int]] = []

    def active(self) -> dict[str, dict[str, Param]]:
        """The line faults in force, with their parameters."""
        out: dict[str, dict[str, Param]] = {}
        if self.no_answer:
            out["no_answer"] = {}
        if self.late_us:
            out["late_answer"] = {"ms": self.late_us / MS}
        if self.corrupt is not None:
            out[self.corrupt.value] = {}
        for fault in state.LineFault:
            left = sum(q.count(fault) for q in self._queued.values())
            if left:
                out[fault.value] = {"count": left}
        if self.not_ready_always or self.not_ready_left or self.not_ready_window_us:
            params: dict[str, Param] = {}
            if self.not_ready_left and not self.not_ready_always:
                params["count"] = self.not_ready_left
            if self.not_ready_window_us:
                params["window_ms"] = self.not_ready_window_us / MS
            out["not_ready"] = params
        return out

    def set_corrupt(self, fault: state.LineFault, on: bool, count: int | None, link: Link) -> None:
        """Every frame to this TES (count None) or the next ``count`` get ``fault``."""
        for queue in self._queued.values():
            while fault in queue:
                queue.remove(fault)
        if self.corrupt is fault:
            self.corrupt = None
        if on and count is None:
            self.corrupt = fault
        elif on and count is not None:
            self.queue(fault, count, link)

    def queue(self, fault: state.LineFault, count: int, link: Link) -> None:
        """The next ``count`` frames to this TES on ``link`` get ``fault``."""
        self._queued[state.link_key(link)].extend([fault] * count)

    def take(self, link: Link) -> state.LineFault | None:
        """The RTU line asks once per frame it delivers to this TES."""
        queue = self._queued[state.link_key(link)]
        return queue.popleft() if queue else self.corrupt

    def pending(self, link: Link) -> state.LineFault | None:
        """What ``take`` would give, without taking it (for the wire trace)."""
        queue = self._queued[state.link_key(link)]
        return queue[0] if queue else self.corrupt

    def set_not_ready(self, on: bool, count: int | None, window_us: int | None) -> None:
        self.not_ready_always = on and count is None and window_us is None
        self.not_ready_left = (count or 0) if on else 0
        self.not_ready_window_us = (window_us or 0) if on else 0

    def not_ready(self, window: bool) -> bool:
        """One more request in the 32-bit area: is it refused as "not ready"?"""
        if self.not_ready_always:
            return True
        if self.not_ready_left:
            self.not_ready_left -= 1
            return True
        return window


class PowerSwitch(Protocol):
    """The 24 V supply of a TES (the Tes itself)."""

    @property
    def powered(self) -> bool: ...

    def power_on(self) -> None: ...

    def power_off(self) -> None: ...


class FaultSurface:
    """Faults of one TES by name: set, cleared, listed (``Tes.inject_fault`` and co)."""

    def __init__(
        self,
        model: TesModel,
        line: LineFaults,
        link: Link,
        di: DigitalInputs,
        set_wiring: Callable[[int, Wiring], None],
        power: PowerSwitch,
    ) -> None:
        self.model = model
        self._line = line
        self._link = link
        self._di = di
        self._set_wiring = set_wiring
        self._power = power

    def names(self) -> Mapping[str, str]:
        return {name: spec.description for name, spec in fault_catalogue(self.model).items()}

    def inject(self, name: str, on: bool, params: Mapping[str, Param]) -> None:
        spec = fault_spec(self.model, name, params)
        if not isinstance(on, bool):
            raise ConfigError(f"fault {name!r}: {on!r} not allowed (allowed: true, false)")
        if name.startswith(("short_", "open_")):
            self._wiring(name, on)
        elif spec.name == "power_off":
            if on and self._power.powered:
                self._power.power_off()
            elif not on and not self._power.powered:
                self._power.power_on()
        elif spec.name == "no_answer":
            self._line.no_answer = on
        elif spec.name == "late_answer":
            self._late(on, params)
        elif spec.name == "not_ready":
            self._not_ready(on, params)
        elif spec.name == "drop_connections":
            if on:
                self._drop()
        else:  # bad_crc, broken_character
            self._line.set_corrupt(state.LineFault(spec.name), on, _count(params), self._link)

    def _drop(self) -> None:
        if not self._line.droppers:
            raise ConfigError(
                "fault 'drop_connections': this TES is not served on a TCP endpoint"
                " (tcp:// or rtu+tcp://) by this run"
            )
        for drop in list(self._line.droppers):
            drop()

    def _wiring(self, name: str, on: bool) -> None:
        kind, _, index = name.partition("_")
        wiring = Wiring.SHORT if kind == "short" else Wiring.OPEN
        i = int(index)
        if on:
            self._set_wiring(i, wiring)
        elif self._di.wiring(i) is wiring:
            self._set_wiring(i, Wiring.OK)

    def _late(self, on: bool, params: Mapping[str, Param]) -> None:
        if not on:
            self._line.late_us = 0
            return
        if "ms" not in params:
            raise ConfigError(f"fault 'late_answer' needs ms = 1..{LATE_MAX_MS}")
        self._line.late_us = round(number("ms", params["ms"], 1, LATE_MAX_MS, " ms") * MS)

    def _not_ready(self, on: bool, params: Mapping[str, Param]) -> None:
        window = None
        if "window_ms" in params:
            ms = number("window_ms", params["window_ms"], 0, NOT_READY_WINDOW_MAX_MS, " ms")
            if ms >= NOT_READY_WINDOW_MAX_MS:
                raise ConfigError(
                    f"fault parameter window_ms: {ms!r} not allowed (allowed 0..<100 ms)"
                )
            window = round(ms * MS)
        self._line.set_not_ready(on, _count(params), window)

    def active(self) -> dict[str, dict[str, Param]]:
        out: dict[str, dict[str, Param]] = {}
        if self.model.safety:
            for i in range(self.model.digital_inputs):
                wiring = self._di.wiring(i)
                if wiring is not Wiring.OK:
                    out[f"{wiring.value}_{i}"] = {}
        if not self._power.powered:
            out["power_off"] = {}
        out.update(self._line.active())
        return out


def _count(params: Mapping[str, Param]) -> int | None:
    if "count" not in params:
        return None
    return int(number("count", params["count"], 1, COUNT_MAX))
