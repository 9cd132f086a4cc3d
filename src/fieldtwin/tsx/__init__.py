"""The TSX Series 7 I/O bus and its intelligent modules."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fieldtwin.tsx.plc import ExchangeResult, ExchangeTimeout, Plc, TextBlock

__all__ = ["ExchangeResult", "ExchangeTimeout", "Plc", "TextBlock"]


def __getattr__(name: str) -> Any:
    # Lazy, so that sans-IO modules importing fieldtwin.tsx.* never pull in the runner.
    if name in __all__:
        from fieldtwin.tsx import plc

        return getattr(plc, name)
    raise AttributeError(name)
