"""The keys every device kind reads the same way: ``inputs`` (a table) and ``faults`` (a list).

    inputs = { "0" = true, "3" = 24.0, a2 = 4.5, "1" = { kind = "pulse", period_s = 2 } }
    faults = ["terminal_block"]          # or, with parameters: [{ name = "late_answer", ms = 200 }]

An input is named as in the console (docs/architecture.md); a value is set as
the input takes it, a table is a signal (docs/signals.md).  Kinds whose older
forms differ (the AEM's list of channel tables, the TES's fault table) read
those in their own adapter.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from fieldtwin.devices.face import Device
from fieldtwin.errors import ConfigError


def apply_inputs(
    device: Device, spec: Mapping[str, object], where: str, base_dir: Path
) -> list[str]:
    """Set or drive every input of ``spec``; the notes the device gave, each with its field."""
    notes: list[str] = []
    for key, value in spec.items():
        field = f"{where}.{key}"
        note = None
        try:
            point = device.input(str(key))
            if isinstance(value, Mapping):
                point.drive(value, where=field, base_dir=base_dir)
            elif isinstance(value, bool | str):
                note = point.set(value)
            elif isinstance(value, int | float):
                note = point.set(float(value))
            else:
                raise ConfigError(f"{value!r} is not a value or a signal table")
        except ConfigError as exc:
            text = str(exc)
            raise ConfigError(text if text.startswith(field) else f"{field}: {text}") from None
        if note is not None:
            notes.append(f"{field}: {note}")
    return notes


def apply_faults(device: Device, names: object, where: str) -> None:
    if not isinstance(names, list):
        raise ConfigError(f"{where}: {names!r} is not a list of fault names")
    for index, entry in enumerate(names):
        try:
            if isinstance(entry, Mapping):  # { name = "late_answer", ms = 200 }
                params = dict(entry)
                name = params.pop("name", None)
                if not isinstance(name, str):
                    raise ConfigError(f"[{index}].name: missing or not a fault name")
                numbers = {k: v for k, v in params.items() if _is_number(v)}
                if len(numbers) != len(params):
                    bad = sorted(str(k) for k in set(params) - set(numbers))
                    raise ConfigError(f"[{index}]: {', '.join(bad)} must be numbers")
                device.fault(name).set(True, **{str(k): v for k, v in numbers.items()})
            else:
                device.fault(str(entry)).set(True)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)
