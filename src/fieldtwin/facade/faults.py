"""Faults by name for a Python user holding a core (``plc.insert(...)``, ``Tes(...)``).

The cores take typed calls only (``aem.set_wire_break(3, True)``); the names of
docs/aem811.md, dem24.md, scm.md and tes.md are each kind's table in
``fieldtwin.devices``.  These two functions find the table of the core's kind::

    from fieldtwin.facade import inject_fault
    inject_fault(aem, "open_3", True)
    inject_fault(tes, "late_answer", True, ms=20)
"""

from __future__ import annotations

from collections.abc import Mapping

from fieldtwin.devices import faults, registry
from fieldtwin.devices.faults import FaultParam


def fault_names(core: object) -> Mapping[str, str]:
    """name -> description of every fault ``core`` accepts."""
    registry.kinds()  # every kind's package loaded: its table registered
    return faults.fault_names(core)


def inject_fault(core: object, name: str, on: bool, **params: FaultParam) -> None:
    """Set (``on``) or clear the fault ``name`` of ``core``; ConfigError naming what is allowed."""
    registry.kinds()
    faults.inject_fault(core, name, on, **params)
