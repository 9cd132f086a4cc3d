"""The faults of the TSX SCM 20/21/22 by name (docs/scm.md), onto its typed calls."""

from __future__ import annotations

from functools import partial

from fieldtwin.devices.faults import NamedFault, SimpleTable, register_faults
from fieldtwin.tsx.scm.module import HARDWARE_FAULTS, ScmModule

_Fault = NamedFault  # of ScmModule


def _self_test(bit: int, mod: ScmModule, on: bool) -> None:
    mod.set_self_test_fault(bit, on)


def _parity(channel: int, mod: ScmModule, on: bool) -> None:
    mod.set_parity_errors(channel, on)


def _format(channel: int, mod: ScmModule, on: bool) -> None:
    mod.set_format_errors(channel, on)


FAULTS = SimpleTable(
    "TSX SCM",
    [
        *(
            _Fault(name, f"self-test fault (fault bit {bit})", partial(_self_test, bit))
            for name, bit in HARDWARE_FAULTS.items()
        ),
        *(
            fault
            for ch in (0, 1)
            for fault in (
                _Fault(
                    f"parity_ch{ch}",
                    f"channel {ch}: every character received with a parity error",
                    partial(_parity, ch),
                ),
                _Fault(
                    f"format_ch{ch}",
                    f"channel {ch}: every character received with a format error",
                    partial(_format, ch),
                ),
            )
        ),
    ],
)
register_faults(ScmModule, FAULTS)
