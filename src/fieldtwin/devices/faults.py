"""Faults by name: each kind's table from a user's fault name to its core's typed calls.

The cores (tsx/, tes/) take typed calls only (``aem.set_wire_break(3, True)``,
``tes.set_no_answer(True)``); the names users write (``open_3``, ``no_answer``,
``late_answer ms=200``) live in each kind's package (``devices/<kind>/faults.py``),
which registers its table for its core class here.  The Device face, the plant
file, and the Python façade (``fieldtwin.facade.inject_fault``) all go through
:func:`table_for`.

A module class only the PLC's type table knows (a test double, a device outside
fieldtwin) may name its faults itself: :class:`NamedFaults`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar, runtime_checkable

from fieldtwin.errors import ConfigError

FaultParam = int | float
C = TypeVar("C")


class FaultTable(Protocol):
    """The faults of one kind of core, by name."""

    def names(self, core: Any) -> Mapping[str, str]:
        """name -> description of every fault ``core`` accepts."""
        ...

    def inject(self, core: Any, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        """Set (``on``) or clear the fault ``name``; ConfigError naming what is allowed."""
        ...


@dataclass(frozen=True, slots=True)
class NamedFault(Generic[C]):
    """One fault without parameters: its name, what it does, the typed call it makes."""

    name: str
    description: str
    apply: Callable[[C, bool], None]


class SimpleTable(Generic[C]):
    """A fixed table of faults without parameters (the TSX modules)."""

    def __init__(self, kind: str, faults: Sequence[NamedFault[C]]) -> None:
        self.kind = kind
        self.faults = {f.name: f for f in faults}

    def names(self, core: Any) -> Mapping[str, str]:
        return {name: f.description for name, f in self.faults.items()}

    def inject(self, core: Any, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        fault = self.faults.get(name)
        if fault is None:
            raise unknown_fault(self.kind, name, self.faults)
        if params:
            raise ConfigError(
                f"fault {name!r} takes no parameters, not {', '.join(sorted(params))}"
            )
        if not isinstance(on, bool):
            raise ConfigError(f"fault {name!r}: {on!r} not allowed (allowed: true, false)")
        fault.apply(core, on)


def unknown_fault(kind: str, name: str, allowed: Mapping[str, object]) -> ConfigError:
    return ConfigError(
        f"unknown fault {name!r} for {kind} (allowed: {', '.join(allowed) or 'none'})"
    )


@runtime_checkable
class NamedFaults(Protocol):
    """A core that names its faults itself (one only the PLC's type table knows)."""

    def fault_names(self) -> Mapping[str, str]: ...

    def inject_fault(self, name: str, active: bool) -> None: ...


class _OwnNames:
    """The table of a :class:`NamedFaults` core: its own names and calls."""

    def names(self, core: Any) -> Mapping[str, str]:
        return dict(core.fault_names())

    def inject(self, core: Any, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        if params:
            raise ConfigError(
                f"fault {name!r} takes no parameters, not {', '.join(sorted(params))}"
            )
        core.inject_fault(name, on)


class _NoFaults:
    """A core without a table and without names of its own: no fault."""

    def names(self, core: Any) -> Mapping[str, str]:
        return {}

    def inject(self, core: Any, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        raise unknown_fault(str(getattr(core, "type_name", type(core).__name__)), name, {})


_tables: dict[type, FaultTable] = {}


def register_faults(core: type, table: FaultTable) -> None:
    """The table of ``core`` and its subclasses (a kind's package, when imported)."""
    _tables[core] = table


def table_for(core: object) -> FaultTable:
    """The fault table of ``core``'s class (the nearest registered base class)."""
    for cls in type(core).__mro__:
        found = _tables.get(cls)
        if found is not None:
            return found
    # a core naming its faults itself; not the cores' own by-name calls, which come here
    own = getattr(type(core), "fault_names", None)
    if isinstance(core, NamedFaults) and not getattr(own, "through_table", False):
        return _OwnNames()
    return _NoFaults()


def fault_names(core: object) -> Mapping[str, str]:
    """name -> description of every fault ``core`` accepts."""
    return table_for(core).names(core)


def inject_fault(core: object, name: str, on: bool, **params: FaultParam) -> None:
    """Set (``on``) or clear the fault ``name`` of ``core`` (``late_answer``, ``ms=200``)."""
    table_for(core).inject(core, name, on, params)
