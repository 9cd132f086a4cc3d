"""The TSX AEM 811's lines for the console's ``status`` and the live view."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from fieldtwin.tsx.aem811.config import ModuleConfig, Rejection
from fieldtwin.tsx.aem811.scaling import Measurement, Scaling
from fieldtwin.tsx.aem811.thresholds import ThresholdDetector

if TYPE_CHECKING:
    from fieldtwin.tsx.aem811.module import Aem811 as Aem811Module

RELAY_LIFE = 300_000_000  # AEM 2.5-2, 8.2: 3 x 10^8 operations


class Aem811(Protocol):
    """What the status lines read of the module (fieldtwin.tsx.aem811.module.Aem811)."""

    config: ModuleConfig
    default_configuration: bool
    rejection: Rejection | None
    thresholds: ThresholdDetector

    @property
    def enabled(self) -> int: ...

    values: list[int]
    measurements: list[Measurement | None]
    relay_operations: list[int]

    @property
    def accelerated(self) -> bool: ...


_SCALING = {Scaling.INPUT_RANGE: "input range", Scaling.STANDARD: "standard", Scaling.USER: "user"}


def channel_flags(m: Measurement | None) -> tuple[str, ...]:
    """A channel's fault flags in the order the console shows them (AEM 4.2, 5.1)."""
    if m is None:
        return ()
    found = (("ELL", m.below), ("continuity", m.continuity), ("overflow", m.overflow))
    return tuple(name for name, on in (*found, ("EHL", m.above)) if on)


def threshold_bits(mod: Aem811, channel: int) -> str:
    """A channel's two threshold bits, level 0 then level 1 ("01")."""
    return "".join(str(mod.thresholds.bits >> (channel + 8 * lv) & 1) for lv in (0, 1))


def details(mod: Aem811) -> dict[str, str]:
    config = mod.config
    lines = {
        "configuration": "default" if mod.default_configuration else "user",
        "sampling": (
            f"accelerated ({bin(mod.enabled).count('1')} x 100 ms)"
            if mod.accelerated
            else f"normal, period {config.period} x 100 ms"
        ),
    }
    if mod.rejection is not None:
        lines["last refusal"] = mod.rejection.reason
    enabled = mod.enabled
    for channel, cfg in enumerate(config.channels):
        text = f"{cfg.range.name}, {_SCALING[cfg.scaling]}"
        if cfg.scaling is Scaling.USER:
            text += f" {cfg.low}..{cfg.high}"
        text += ", sqrt" * cfg.sqrt + ", continuity test" * cfg.continuity
        state = "inhibited" if not enabled >> channel & 1 else f"= {mod.values[channel]}"
        m = mod.measurements[channel]
        faults = channel_flags(m)
        thresholds = threshold_bits(mod, channel)
        text += f"; {state}; thresholds {mod.thresholds.values[0][channel]}/"
        text += f"{mod.thresholds.values[1][channel]} bits {thresholds}"
        if faults:
            text += f"; FAULT {' '.join(faults)}"
        lines[f"channel {channel}"] = text
    total = sum(mod.relay_operations)
    lines["relay operations"] = (
        f"{total} (max per channel {max(mod.relay_operations)} of a {RELAY_LIFE:.0e} life)"
    )
    return lines


def lines(mod: Aem811Module) -> dict[str, str]:
    """Every status line: the module's own, then the AEM's."""
    return {**mod.status(), **details(mod)}
