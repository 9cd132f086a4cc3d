"""The one registry of device kinds: TSX module kinds and TES models alike.

Each line of :data:`ADAPTERS` names an adapter module of this package; each
adapter exposes ``KINDS: tuple[DeviceKind, ...]``.  Adding a device is one core
package, one adapter file and one line here (or, outside fieldtwin, one call to
:func:`register`: tests/devices/ adds a made-up device that way).  A module
kind's core class is also given to the PLC's type table so that
``plc.insert(type_name)`` finds it.
"""

from __future__ import annotations

import importlib

from fieldtwin.devices.face import Family
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.devices.module import GENERIC_SCHEMA, build_generic
from fieldtwin.errors import ConfigError
from fieldtwin.tsx import registry as plc_types

ADAPTERS = (
    "fieldtwin.devices.aem811",
    "fieldtwin.devices.dem24",
    "fieldtwin.devices.discrete",
    "fieldtwin.devices.scm",
    "fieldtwin.devices.tes",
)

_kinds: dict[tuple[Family, str], DeviceKind] = {}
_loaded: list[bool] = []


def norm(name: str) -> str:
    """``"TSX AEM 811"``, ``"tsx aem  811"``; a TES model also as ``"8EA"`` or ``"tes 8 ea"``."""
    return "".join(name.upper().split())


def register(kind: DeviceKind) -> None:
    """Add a kind (the adapters' KINDS, or a device outside fieldtwin: after them)."""
    _load()
    _add(kind)


def _load() -> None:
    if _loaded:
        return
    _loaded.append(True)
    for path in ADAPTERS:
        adapter = importlib.import_module(path)
        for kind in adapter.KINDS:
            _add(kind)


def _add(kind: DeviceKind) -> None:
    _kinds[(kind.family, norm(kind.name))] = kind
    if kind.core is not None:
        plc_types.register(kind.name, kind.core)


def families() -> list[Family]:
    """Every family with a kind registered, in registration order (fieldtwin's first)."""
    _load()
    return list(dict.fromkeys(f for f, _ in _kinds))


def kinds(family: Family | None = None) -> list[DeviceKind]:
    """Every kind, in registration order."""
    _load()
    return [k for (f, _), k in _kinds.items() if family in (None, f)]


def kind_named(name: str, family: Family) -> DeviceKind:
    """The kind called ``name``; a module class only the PLC knows gets the generic face."""
    _load()
    key = norm(name)
    found = _kinds.get((family, key))
    if found is None and family is Family.TES and not key.startswith("TES"):
        found = _kinds.get((family, "TES" + key))
    if found is not None:
        return found
    if family is Family.MODULE and " ".join(name.upper().split()) in plc_types.module_types():
        return DeviceKind(name, Family.MODULE, GENERIC_SCHEMA, build_generic)
    allowed = ", ".join(k.name for k in kinds(family)) or "none installed"
    raise ConfigError(f"unknown {family.what} {name!r} (allowed: {allowed})")
