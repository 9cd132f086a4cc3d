"""The Device face of the plain discrete input and output modules (fieldtwin.tsx.discrete).

The adapter is :mod:`.device`; this package re-exports its names."""

from fieldtwin.devices.discrete.device import (
    KINDS,
    LEVELS,
    SCHEMA,
    DiscreteDevice,
)

__all__ = [
    "KINDS",
    "LEVELS",
    "SCHEMA",
    "DiscreteDevice",
]
