"""What the time and assertion helpers act on: a plant, a PLC, a TES, or a running plant.

Each kind of target answers the same few questions -- the simulated time, an
object's value without side effect, a device's LEDs and state, a name for
messages -- and runs its own simulated time.  In-process targets (``Plant``,
``Plc``, ``Tes``) run their SimClock event by event; a running plant
(:class:`fieldtwin.testing.process.RunningPlant`) is asked through its control API.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from fieldtwin.clock import S, SimClock
from fieldtwin.devices.face import Device, device_id
from fieldtwin.devices.module import ModuleDevice
from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import Tes, tes_registers
from fieldtwin.plant import Plant
from fieldtwin.tsx.addressing import parse_module
from fieldtwin.tsx.bus import Pacer
from fieldtwin.tsx.plc import Plc


def time_text(t_s: float) -> str:
    """``t = 15.000 s``; microseconds shown when the instant is not a whole millisecond."""
    us = round(t_s * S)
    return f"t = {t_s:.3f} s" if us % 1000 == 0 else f"t = {t_s:.6f} s"


class Target(Protocol):
    """The questions every helper asks of what it tests."""

    @property
    def label(self) -> str: ...

    def now_s(self) -> float: ...

    def value(self, name: str) -> int: ...

    def leds(self, device: str | None) -> tuple[str, dict[str, str]]: ...

    def state(self, device: str | None) -> tuple[str, str]: ...

    def default_show(self) -> list[str]: ...

    def advance_to(self, t_s: float) -> None: ...

    def run_until(
        self, predicate: Callable[[], object], within_s: float, step_s: float | None
    ) -> tuple[bool, object]: ...


def _split(name: str) -> tuple[str | None, str]:
    """``"tes1:0x005"`` -> ("tes1", "0x005"); ``"IW5,0"`` -> (None, "IW5,0")."""
    device, sep, rest = name.partition(":")
    if sep and device.strip() and rest.strip():
        return device.strip(), rest.strip()
    return None, name.strip()


class _Clocked:
    """Simulated time run event by event on a SimClock (or by the runner pacing it)."""

    clock: SimClock
    pacer: Callable[[], Pacer | None]

    def now_s(self) -> float:
        return self.clock.now / S

    def advance_to(self, t_s: float) -> None:
        target = round(t_s * S) if t_s * S < float("inf") else None
        if target is None or target < self.clock.now:
            raise ConfigError(
                f"cannot advance to t = {t_s:g} s: simulated time is already"
                f" {time_text(self.now_s())[4:]} and never goes back"
            )
        pacer = self.pacer()
        if pacer is not None:
            pacer.advance(target - self.clock.now)
        else:
            self.clock.run_until(target)

    def run_until(
        self, predicate: Callable[[], object], within_s: float, step_s: float | None
    ) -> tuple[bool, object]:
        end = self.clock.now + round(within_s * S)
        last = predicate()
        if last:
            return True, last
        pacer = self.pacer()
        step = round(step_s * S) if step_s else None
        if pacer is not None:

            def check() -> bool:
                nonlocal last
                last = predicate()
                return bool(last)

            done = pacer.run_until(check, end - self.clock.now)
            return bool(done), last
        while self.clock.now < end:
            if step is not None:
                self.clock.run_until(min(end, self.clock.now + step))
            else:
                deadline = self.clock.next_deadline()
                self.clock.run_until(end if deadline is None or deadline > end else deadline)
            last = predicate()
            if last:
                return True, last
        return False, last


@dataclass
class PlantTarget(_Clocked):
    plant: Plant

    def __post_init__(self) -> None:
        self.clock = self.plant.clock
        plc = self.plant.plc
        self.pacer = (lambda: plc.runner) if plc is not None else (lambda: None)

    @property
    def label(self) -> str:
        return f"plant {self.plant.name}"

    def _device(self, ident: str) -> Device:
        devices = self.plant.devices
        for device in devices:
            if device_id(device, devices) == ident.lower():
                return device
        have = ", ".join(device_id(d, devices) for d in devices) or "none"
        raise ConfigError(f"{self.label}: no device {ident!r} (have: {have})")

    def value(self, name: str) -> int:
        device, obj = _split(name)
        if device is not None:
            return self._device(device).objects().peek(obj)
        if self.plant.plc is None:
            raise ConfigError(f"{self.label} has no PLC: name a device's object, e.g. 'tes1:0x005'")
        return self.plant.plc.read(obj)

    def _needs(self, device: str | None) -> Device:
        if device is None:
            raise ConfigError(f"{self.label}: name the device (e.g. '5' or 'tes1')")
        return self._device(device)

    def leds(self, device: str | None) -> tuple[str, dict[str, str]]:
        found = self._needs(device)
        return f"{found.kind} {device}", {k: str(v) for k, v in found.status().leds}

    def state(self, device: str | None) -> tuple[str, str]:
        found = self._needs(device)
        return f"{found.kind} {device}", found.status().state

    def default_show(self) -> list[str]:
        return list(self.plant.plc.watch) if self.plant.plc is not None else []


@dataclass
class PlcTarget(_Clocked):
    plc: Plc

    def __post_init__(self) -> None:
        self.clock = self.plc.clock
        self.pacer = lambda: self.plc.runner

    @property
    def label(self) -> str:
        return f"PLC {self.plc.model.name}"

    def value(self, name: str) -> int:
        return self.plc.read(name)

    def _module(self, device: str | None) -> Device:
        if device is None:
            raise ConfigError(f"{self.label}: name the module by its slot (e.g. '5')")
        rack, slot = parse_module(device)
        return ModuleDevice(self.plc.module(rack, slot), self.plc)

    def leds(self, device: str | None) -> tuple[str, dict[str, str]]:
        module = self._module(device)
        return f"{module.kind} {device}", {k: str(v) for k, v in module.status().leds}

    def state(self, device: str | None) -> tuple[str, str]:
        module = self._module(device)
        return f"{module.kind} {device}", module.status().state

    def default_show(self) -> list[str]:
        return list(self.plc.watch)


@dataclass
class TesTarget(_Clocked):
    tes: Tes

    def __post_init__(self) -> None:
        self.clock = self.tes.clock
        self.pacer = lambda: None
        self._words = tes_registers(self.tes)

    @property
    def label(self) -> str:
        return f"{self.tes.model.name} slave {self.tes.slave}"

    def value(self, name: str) -> int:
        return self._words.peek(name)

    def leds(self, device: str | None) -> tuple[str, dict[str, str]]:
        return self.label, {k: str(v) for k, v in self.tes.leds.items()}

    def state(self, device: str | None) -> tuple[str, str]:
        return self.label, "on" if self.tes.powered else "off"

    def default_show(self) -> list[str]:
        return []


def target_of(obj: object) -> Target:
    """The helpers' view of a Plant, Plc, Tes or RunningPlant (TypeError otherwise)."""
    from fieldtwin.testing.process import RunningPlant, RunningTarget

    if isinstance(obj, RunningTarget):
        return obj
    if isinstance(obj, Plant):
        return PlantTarget(obj)
    if isinstance(obj, Plc):
        return PlcTarget(obj)
    if isinstance(obj, Tes):
        return TesTarget(obj)
    if isinstance(obj, RunningPlant):
        return obj.target()
    raise TypeError(
        f"{obj!r} is not a plant, a PLC, a TES or a running plant"
        " (the fixtures plant, plc, tes, running_plant give one)"
    )
