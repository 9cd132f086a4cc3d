"""The Device face of the Leroy TES remote I/O terminals (docs/tes.md).

The adapter is :mod:`.device`; this package re-exports its names."""

from fieldtwin.devices.tes.device import (
    GROUP,
    KINDS,
    SCHEMA,
    TesDevice,
    TesRegisters,
)

__all__ = [
    "GROUP",
    "KINDS",
    "SCHEMA",
    "TesDevice",
    "TesRegisters",
]
