"""Errors by culprit (DESIGN rule 7).

A device's answer to bad input (report H'FD', Modbus exception, status bit) is
data, never one of these exceptions.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence


class FieldtwinError(Exception):
    """Root of every error fieldtwin raises."""


class ConfigError(FieldtwinError, ValueError):
    """The user's own mistake: a plant file, an object name, an argument."""


def refuse_unknown_keys(table: Collection[str], allowed: Sequence[str], where: str) -> None:
    """ConfigError ``{where}: unknown key(s) a, b (allowed: ...)`` when ``table`` has keys
    ``allowed`` does not list (in sorted order; the allowed ones in their own)."""
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ConfigError(
            f"{where}: unknown key(s) {', '.join(unknown)} (allowed: {', '.join(allowed)})"
        )


class ProtocolError(FieldtwinError):
    """A peer's bytes, or an event a state machine cannot take in its state."""


class TransportError(FieldtwinError):
    """An endpoint is closed, broken or timed out."""
