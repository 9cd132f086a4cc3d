"""Module types by the names users write (``type = "TSX AEM 811"``).

Each device package exposes ``MODULE_TYPES: Mapping[str, type[IntelligentModule]]``;
they are imported lazily so that a plant only loads the modules it uses.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any

from fieldtwin.errors import ConfigError

PROVIDERS = ("fieldtwin.tsx.aem811", "fieldtwin.tsx.dem24", "fieldtwin.tsx.scm")
_extra: dict[str, Any] = {}


def register(type_name: str, cls: Any) -> None:
    """Add a module type (tests use this for their test double)."""
    _extra[_norm(type_name)] = cls


def _norm(name: str) -> str:
    return " ".join(name.upper().split())


def module_types() -> dict[str, Any]:
    types: dict[str, Any] = {}
    for provider in PROVIDERS:
        try:
            package = importlib.import_module(provider)
        except ModuleNotFoundError as exc:
            if exc.name != provider:
                raise
            continue
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
