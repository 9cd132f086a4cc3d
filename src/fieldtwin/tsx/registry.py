"""Module classes by the names users write (``type = "TSX AEM 811"``), for ``Plc.insert``.

Every sub-package of ``fieldtwin.tsx`` that exposes
``MODULE_TYPES: Mapping[str, type[IntelligentModule]]`` is found by looking
(no list to keep), lazily so that a plant only loads what it uses;
``register`` adds a class from elsewhere (the device registry,
``fieldtwin.devices.registry``, gives it every module kind it knows, and tests
their doubles).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fieldtwin.errors import ConfigError

_extra: dict[str, Any] = {}


def register(type_name: str, cls: Any) -> None:
    """Add a module type (the device registry, and tests for their test double)."""
    _extra[_norm(type_name)] = cls


def _norm(name: str) -> str:
    return " ".join(name.upper().split())


def _providers() -> list[str]:
    return [
        f"fieldtwin.tsx.{info.name}"
        for info in pkgutil.iter_modules([str(Path(__file__).parent)])  # fieldtwin.tsx
        if info.ispkg
    ]


def module_types() -> dict[str, Any]:
    types: dict[str, Any] = {}
    for provider in _providers():
        package = importlib.import_module(provider)
        found: Mapping[str, Any] = getattr(package, "MODULE_TYPES", {})
        types.update({_norm(k): v for k, v in found.items()})
    types.update(_extra)
    return types


def module_class(type_name: str) -> Any:
    types = module_types()
    try:
        return types[_norm(type_name)]
    except KeyError:
        allowed = ", ".join(sorted(types)) or "none installed"
        raise ConfigError(f"unknown module type {type_name!r} (allowed: {allowed})") from None
