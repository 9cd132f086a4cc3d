"""The faults of the TSX DEM 2412 / 2413 by name (docs/dem24.md), onto its typed calls."""

from __future__ import annotations

from fieldtwin.devices.faults import NamedFault, SimpleTable, register_faults
from fieldtwin.tsx.dem24.module import Dem24


def _terminal_block(mod: Dem24, on: bool) -> None:
    mod.set_terminal_block(not on)


def _supply(mod: Dem24, on: bool) -> None:
    mod.set_supply(not on)


FAULTS = SimpleTable(
    "TSX DEM 24",
    [
        NamedFault("terminal_block", "TSX BLK4 terminal block removed", _terminal_block),
        NamedFault("supply", "external input supply lost", _supply),
        NamedFault(
            "pulses", "synchronization pulses no longer reach IN-SYN", Dem24.set_pulses_lost
        ),
    ],
)
register_faults(Dem24, FAULTS)
