"""The Device face of the TSX SCM 20xy / 21xy / 22xy (docs/scm.md).

The adapter is :mod:`.device`; this package re-exports its names."""

from fieldtwin.devices.scm.device import (
    GROUP,
    KINDS,
    SCHEMA,
    ScmDevice,
)

__all__ = [
    "GROUP",
    "KINDS",
    "SCHEMA",
    "ScmDevice",
]
