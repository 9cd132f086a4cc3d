"""The Device face of the TSX AEM 811 (docs/aem811.md).

The adapter is :mod:`.device`; this package re-exports its names."""

from fieldtwin.devices.aem811.device import (
    CHANNELS,
    KINDS,
    SCHEMA,
    Aem811Device,
    build,
)

__all__ = [
    "CHANNELS",
    "KINDS",
    "SCHEMA",
    "Aem811Device",
    "build",
]
