"""Outages that last: a TES's 24 V off for a while, on the simulated clock (issue 22 item 4).

``power_cycle(clock, device, seconds)`` cuts the supply of a device that has the
``power_off`` fault (a TES, §1) and schedules its return ``seconds`` later on the
plant's clock: during the outage the TES does not answer and its LEDs are off;
at its end the power comes back as after any power-on (RAM reset, EEPROM reload,
the restart bit).  Without ``seconds`` (or 0) the cycle is instantaneous, as it
always was.  The pending returns are kept on the clock (``clock.shared``), by
device, so a second cycle during an outage is answered with when power returns.
"""

from __future__ import annotations

import math

from fieldtwin.clock import Handle, S, SimClock, seconds
from fieldtwin.devices.face import Device
from fieldtwin.errors import ConfigError

MAX_OUTAGE_S = 3600.0  # the longest outage one call asks (as the PLC's power break)
_SHARED = "outages"  # clock.shared key: {id(device): Handle of the power's return}


class OutageBusy(ConfigError):
    """A power cycle asked while the device's outage is still on (answered 409)."""


def check_seconds(value: object, where: str = "seconds") -> float:
    """An outage's duration in simulated seconds, 0..MAX_OUTAGE_S; ConfigError naming
    ``where`` and what is allowed."""
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not math.isfinite(value)
        or not 0 <= value <= MAX_OUTAGE_S
    ):
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed: simulated seconds from 0 to"
            f" {MAX_OUTAGE_S:g}; 0 or none: off and on at once)"
        )
    return float(value)


def _pending(clock: SimClock) -> dict[int, Handle]:
    found: dict[int, Handle] = clock.shared.setdefault(_SHARED, {})
    return found


def power_back_at(clock: SimClock, device: Device) -> int | None:
    """When the outage in progress on ``device`` ends (µs), or None when it is powered."""
    handle = _pending(clock).get(id(device))
    return handle.time if handle is not None and handle.active else None


def power_cycle(
    clock: SimClock, device: Device, duration_s: float | None = None, label: str = ""
) -> int | None:
    """24 V off now, on again after ``duration_s`` simulated seconds (None or 0: at
    once).  Returns when the power comes back (µs), None if it is back already.
    OutageBusy while an outage of the device is in progress."""
    name = label or f"{device.kind} {device.address}"
    duration = check_seconds(0.0 if duration_s is None else duration_s, f"{name}: seconds")
    fault = device.fault("power_off")  # ConfigError for a device without a 24 V supply
    pending = _pending(clock)
    back = power_back_at(clock, device)
    if back is not None:
        raise OutageBusy(
            f"{name} is off until t = {back / S:.3f} s (an outage is in progress;"
            " ask again once the power is back)"
        )
    fault.set(True)
    if duration == 0:
        fault.clear()
        return None
    key = id(device)

    def power_on(now: int) -> None:
        pending.pop(key, None)
        fault.clear()  # power on: RAM reset, EEPROM reload (§1)

    pending[key] = handle = clock.call_later(seconds(duration), power_on)
    return handle.time


__all__ = ["MAX_OUTAGE_S", "OutageBusy", "check_seconds", "power_back_at", "power_cycle"]
