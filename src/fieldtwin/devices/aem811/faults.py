"""The faults of the TSX AEM 811 by name (docs/aem811.md, "Faults"), onto its typed calls."""

from __future__ import annotations

from functools import partial

from fieldtwin.devices.faults import NamedFault, SimpleTable, register_faults
from fieldtwin.tsx.aem811.module import Aem811

_Fault = NamedFault  # of Aem811


def _open(channel: int, mod: Aem811, on: bool) -> None:
    mod.set_wire_break(channel, on)


def _terminal_block(mod: Aem811, on: bool) -> None:
    mod.set_terminal_block(not on)


FAULTS = SimpleTable(
    "TSX AEM 811",
    [
        _Fault(
            "processor",
            "processor or bus interface failure: blocking fault, F LED (until power-up)",
            Aem811.set_processor_fault,
        ),
        _Fault(
            "terminal_block",
            "terminal block open or not fitted (bit 16, IWxy,0,A): module stops",
            _terminal_block,
        ),
        _Fault(
            "converter",
            "analog to digital converter fault (bit 17): module stops",
            Aem811.set_converter_fault,
        ),
        _Fault(
            "relay",
            "input relay fault (bit 18): found by the next initial self-test, module stops",
            Aem811.set_relay_fault,
        ),
        *(
            _Fault(
                f"open_{c}",
                f"channel {c} wire cut: the input is an open circuit",
                partial(_open, c),
            )
            for c in range(8)
        ),
    ],
)
NAMES = FAULTS.names(None)
register_faults(Aem811, FAULTS)
