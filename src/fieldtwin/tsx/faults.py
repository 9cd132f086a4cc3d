"""Fault latching of intelligent modules (AEM 4.4-1).

Each fault of the fault bit string is latched on its own.  IWxy,0,4/6/7 show a
category while one of its faults is present or latched; reading the fault bit
string acknowledges every latched fault: one already gone leaves at the read, one
still present leaves when it ends.  So "the message read after detection of fault
nbr. 1 will not contain fault nbr. 2", and fault 2 keeps the bits at 1 after
fault 1 ends, until a new read.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass


class FaultCategory(enum.Enum):
    """Where a fault shows in IWxy,0 (AEM 4.4-1)."""

    BLOCKING = "blocking"  # IWxy,0,8, F LED, module out of service
    MODULE = "module"  # IWxy,0,6 (memorised) and 4, Ixy,S, module to Stop
    APPLICATION = "application"  # IWxy,0,7 (memorised) and 4, ERR LED, module keeps running


@dataclass(slots=True)
class _Latch:
    category: FaultCategory
    active: bool = False
    latched: bool = False  # shown in IWxy,0 until acknowledged and gone
    acknowledged: bool = False


class FaultLatches:
    """The faults of one module, by their bit number in the fault bit string."""

    def __init__(self, on_change: Callable[[], None] | None = None) -> None:
        self._latches: dict[int, _Latch] = {}
        self._on_change = on_change  # told of every change (the module's bus face)

    def _changed(self) -> None:
        if self._on_change is not None:
            self._on_change()

    def clear(self) -> None:
        self._latches.clear()
        self._changed()

    def category(self, bit: int) -> FaultCategory | None:
        latch = self._latches.get(bit)
        return latch.category if latch is not None else None

    def set(self, bit: int, active: bool, category: FaultCategory) -> None:
        latch = self._latches.get(bit)
        if latch is None:
            if not active:
                return
            latch = self._latches[bit] = _Latch(category)
        self._changed()
        if active and not latch.active:
            latch.active = True
            latch.latched = True
            latch.acknowledged = False
        elif not active and latch.active:
            latch.active = False
            if latch.acknowledged:
                latch.latched = False  # read while present: goes when the fault ends

    def active(self, bit: int) -> bool:
        latch = self._latches.get(bit)
        return bool(latch and latch.active)

    def any(self, category: FaultCategory, *, memorised: bool) -> bool:
        if not self._latches:  # the usual case: no fault was ever raised
            return False
        return any(
            f.category is category and (f.active or (memorised and f.latched))
            for f in self._latches.values()
        )

    def read(self, length: int) -> bytes:
        """The fault bit string (bit n in byte n // 8); acknowledges every latch."""
        self._changed()
        data = bytearray(length)
        for bit, latch in self._latches.items():
            if latch.active or latch.latched:
                data[bit // 8] |= 1 << (bit % 8)
        for latch in self._latches.values():
            if latch.active:
                latch.acknowledged = True
            else:
                latch.latched = False
        return bytes(data)
