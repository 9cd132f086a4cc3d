"""The faults of a TES by name (docs/tes.md, "Faults"), onto the TES core's typed calls.

One catalogue per model (built once per model): wiring faults of the TES
32ET-S inputs (``short_<i>``, ``open_<i>``, §4.1.5), line faults aimed at this
one TES whatever else shares its line (``no_answer``, ``late_answer``,
``bad_crc``, ``broken_character``, ``not_ready``, ``drop_connections``) and
``power_off`` (24 V removed, §1).  :data:`FAULTS` maps each name onto
``Tes.set_wiring``, ``Tes.set_no_answer``, ``Tes.set_late_answer``...
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from fieldtwin.devices.faults import FaultParam, register_faults
from fieldtwin.errors import ConfigError
from fieldtwin.tes import state
from fieldtwin.tes.digital import Wiring
from fieldtwin.tes.faults import COUNT_MAX, LATE_MAX_MS, NOT_READY_WINDOW_MAX_MS, number
from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import TesModel


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


class TesFaults:
    """The fault table of every TES model: names checked, then the core's typed calls."""

    def names(self, core: Any) -> Mapping[str, str]:
        tes = _tes(core)
        return {name: spec.description for name, spec in fault_catalogue(tes.model).items()}

    def inject(self, core: Any, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        tes = _tes(core)
        spec = fault_spec(tes.model, name, params)
        if not isinstance(on, bool):
            raise ConfigError(f"fault {name!r}: {on!r} not allowed (allowed: true, false)")
        if name.startswith(("short_", "open_")):
            _wiring(tes, name, on)
        elif spec.name == "power_off":
            if on and tes.powered:
                tes.power_off()
            elif not on and not tes.powered:
                tes.power_on()
        elif spec.name == "no_answer":
            tes.set_no_answer(on)
        elif spec.name == "late_answer":
            _late(tes, on, params)
        elif spec.name == "not_ready":
            tes.set_not_ready(on, _count(params), params.get("window_ms"))
        elif spec.name == "drop_connections":
            if on:
                tes.drop_connections()
        else:  # bad_crc, broken_character
            tes.set_corrupt_frames(state.LineFault(spec.name), on, _count(params))


def _tes(core: object) -> Tes:
    assert isinstance(core, Tes)
    return core


def _wiring(tes: Tes, name: str, on: bool) -> None:
    kind, _, index = name.partition("_")
    wiring = Wiring.SHORT if kind == "short" else Wiring.OPEN
    i = int(index)
    if on:
        tes.set_wiring(i, wiring)
    elif tes.di.wiring(i) is wiring:
        tes.set_wiring(i, Wiring.OK)


def _late(tes: Tes, on: bool, params: Mapping[str, FaultParam]) -> None:
    if not on:
        tes.set_late_answer(0)
        return
    if "ms" not in params:
        raise ConfigError(f"fault 'late_answer' needs ms = 1..{LATE_MAX_MS}")
    tes.set_late_answer(number("ms", params["ms"], 1, LATE_MAX_MS, " ms"))


def _count(params: Mapping[str, FaultParam]) -> int | None:
    if "count" not in params:
        return None
    return int(number("count", params["count"], 1, COUNT_MAX))


FAULTS = TesFaults()
register_faults(Tes, FAULTS)
