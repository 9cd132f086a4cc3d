"""The Device face of the TSX DEM 2412 / 2413 (docs/dem24.md).

The adapter is :mod:`.device`; this package re-exports its names."""

from fieldtwin.devices.dem24.device import (
    KINDS,
    SCHEMA,
    Dem24Device,
)

__all__ = [
    "KINDS",
    "SCHEMA",
    "Dem24Device",
]
