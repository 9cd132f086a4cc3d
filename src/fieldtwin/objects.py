"""PL7 object names of a module in a rack: ``IW5,0``, ``OW23,1,8``, ``I5,S``, ``O7,0``.

The discrete interface is 16 bits ``Ixy,0..F`` / ``Oxy,0..F`` plus the module fault
bit ``Ixy,S``; the register interface is 8 input words ``IWxy,0..7`` and 8 output
words ``OWxy,0..7``, a bit of which is ``IWxy,i,j`` (AEM 2.4-2, 2.4-3; DEM 2.4-1).
x is the rack and y the slot; rack 0 may be written without its digit (``IW5,0``),
AEM 1.1-1 ("for a module in rack 2 ... slot number 3: IW23,0").

A Text Block address ``TXTi,M = H'xyzz'`` holds the rack in the first hex digit, the
slot in the second and the channel (00, 01) or 63 (the module system) in the low byte
(AEM 4.4-1 "TXTi,M = H'xy..' where x = rack nbr., y = slot nbr., .. = Ch. nbr. 00 or
63"; SCM 2.2).

These names sit in the kernel, below both the PLC (tsx/) and PL7 programs (pl7/);
``fieldtwin.tsx.addressing`` keeps giving them.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass
from typing import NamedTuple

from fieldtwin.errors import ConfigError

# AEM 5.1 I/O configuration table (MODULE 0..7 per rack) and 6.1-1 (a double rack is
# two racks, "slots 0 to 7 of the lower rack"): 8 slots per rack.  The rack number is
# one digit of the object name; racks 0..7 is our reading (docs/manual-notes.md).
RACKS = range(8)
SLOTS = range(8)
# AEM 1.2-2, 6.1-1: on a TSX 47-20 an intelligent module sits in the first 4 slots of
# the basic configuration (rack 0).
TSX_47_20_INTELLIGENT_SLOTS = range(4)
WORD_INDEXES = range(8)  # AEM 2.4-3: 8 input and 8 output register words
BITS = range(16)  # bits 0..F of a word, discrete bits 0..F (AEM 2.4-2)

TXT_MODULE_SYSTEM = 0x63  # H'xy63': the module system (same as textblock.MODULE_SYSTEM)
TXT_CHANNELS = (0x00, 0x01, TXT_MODULE_SYSTEM)  # AEM 4.4-1, SCM 2.2

_ALLOWED_FORMS = "IWxy,i  OWxy,i  IWxy,i,j  OWxy,i,j  Ixy,i  Oxy,i  Ixy,S"


DATA_WORDS = 4096  # internal words W0..W4095 (Text Block tables, manual-notes F-12)


class ObjectKind(enum.Enum):
    IW = "IW"  # input register word
    OW = "OW"  # output register word
    I = "I"  # noqa: E741  discrete input bit (the manuals' own letter)
    O = "O"  # noqa: E741  discrete output bit
    FAULT = "S"  # Ixy,S module fault bit


_WORD_KINDS = (ObjectKind.IW, ObjectKind.OW)


@dataclass(frozen=True, slots=True)
class ObjectRef:
    """One PL7 object of the module at (rack, slot)."""

    kind: ObjectKind
    rack: int
    slot: int
    index: int | None = None  # word index 0..7 (IW/OW) or bit 0..F (I/O); None for S
    bit: int | None = None  # bit 0..F of a register word, else None

    def __post_init__(self) -> None:
        shown = f"{self.kind.name} rack {self.rack} slot {self.slot} {self.index},{self.bit}"
        _check_range("rack", self.rack, RACKS, shown)
        _check_range("slot", self.slot, SLOTS, shown)
        if self.kind in _WORD_KINDS:
            _check_range("word index", self.index, WORD_INDEXES, shown)
            if self.bit is not None:
                _check_range("bit", self.bit, BITS, shown)
        elif self.kind is ObjectKind.FAULT:
            if self.index is not None or self.bit is not None:
                raise ConfigError(f"{shown!r}: the fault bit Ixy,S has no index or bit")
        else:
            _check_range("bit", self.index, BITS, shown)
            if self.bit is not None:
                raise ConfigError(f"{shown!r}: a discrete bit Ixy,i / Oxy,i has no sub-bit")

    @property
    def is_bit(self) -> bool:
        return self.kind not in _WORD_KINDS or self.bit is not None

    @property
    def is_output(self) -> bool:
        return self.kind in (ObjectKind.OW, ObjectKind.O)

    @property
    def is_word(self) -> bool:
        return not self.is_bit

    @property
    def module(self) -> tuple[int, int]:
        """(rack, slot) of the module the object belongs to."""
        return (self.rack, self.slot)

    def word(self) -> ObjectRef:
        """``IWxy,i`` of ``IWxy,i,j`` (the word holding a register bit)."""
        if self.kind not in _WORD_KINDS:
            raise ConfigError(f"{str(self)!r} is not a register word or register bit")
        return ObjectRef(self.kind, self.rack, self.slot, self.index, None)

    def __str__(self) -> str:
        return format_object(self)


def _check_range(what: str, value: int | None, allowed: range, token: str) -> None:
    if value is None or value not in allowed:
        raise ConfigError(
            f"{token!r}: {what} {value} out of range (allowed {allowed.start}..{allowed.stop - 1})"
        )


def format_module(rack: int, slot: int) -> str:
    """The xy of an object name: rack 0 written without its digit (``5``, ``23``)."""
    return f"{slot}" if rack == 0 else f"{rack}{slot}"


def parse_module(token: str) -> tuple[int, int]:
    """A module address ``5``, ``05`` or ``23`` -> (rack, slot)."""
    text = token.strip()
    if not text.isdigit() or not text.isascii():
        raise ConfigError(
            f"{token!r}: not a module address (allowed y or xy: rack {RACKS.start}.."
            f"{RACKS.stop - 1}, slot {SLOTS.start}..{SLOTS.stop - 1}, e.g. 5 or 23)"
        )
    return _parse_module(token, text)


def format_object(ref: ObjectRef) -> str:
    """Canonical name: uppercase, rack 0 without its digit (``IW5,0,C``, ``I23,S``)."""
    xy = format_module(ref.rack, ref.slot)
    if ref.kind is ObjectKind.FAULT:
        return f"I{xy},S"
    if ref.kind in _WORD_KINDS:
        tail = "" if ref.bit is None else f",{ref.bit:X}"
        return f"{ref.kind.value}{xy},{ref.index}{tail}"
    return f"{ref.kind.value}{xy},{ref.index:X}"


# Whitespace is tolerated around the parts: the manuals themselves print "O 6,0".
_OBJECT_RE = re.compile(
    r"^(?P<kind>IW|OW|I|O)\s*(?P<xy>[0-9]+)\s*,\s*(?P<i>[0-9A-Z]+)(?:\s*,\s*(?P<j>[0-9A-Z]+))?$"
)


def parse_object(token: str) -> ObjectRef:
    """``'iw23,0,c'`` -> ObjectRef(IW, rack 2, slot 3, index 0, bit 12)."""
    text = token.strip().upper()
    match = _OBJECT_RE.match(text)
    if match is None:
        raise ConfigError(f"{token!r}: unknown object (allowed {_ALLOWED_FORMS})")
    rack, slot = _parse_module(token, match["xy"])
    letters, i, j = match["kind"], match["i"], match["j"]
    if letters in ("IW", "OW"):
        index = _parse_digit(token, "word index", i, 10, WORD_INDEXES)
        bit = None if j is None else _parse_digit(token, "bit", j, 16, BITS)
        return ObjectRef(ObjectKind(letters), rack, slot, index, bit)
    if j is not None:
        raise ConfigError(f"{token!r}: a discrete bit takes no second index (allowed Ixy,i Oxy,i)")
    if i == "S":
        if letters == "O":
            raise ConfigError(f"{token!r}: only inputs have a fault bit (allowed Ixy,S)")
        return ObjectRef(ObjectKind.FAULT, rack, slot)
    bit = _parse_digit(token, "bit", i, 16, BITS)
    return ObjectRef(ObjectKind(letters), rack, slot, bit)


def _parse_module(token: str, xy: str) -> tuple[int, int]:
    # AEM 1.1-1: "IW23,0" rack 2 slot 3; rack 0 written "5" or "05"
    if len(xy) == 1:
        rack, slot = 0, int(xy)
    elif len(xy) == 2:
        rack, slot = int(xy[0]), int(xy[1])
    else:
        raise ConfigError(
            f"{token!r}: module address {xy!r} is not rack and slot (allowed y or xy,"
            f" rack {RACKS.start}..{RACKS.stop - 1}, slot {SLOTS.start}..{SLOTS.stop - 1})"
        )
    for what, value, allowed in (("rack", rack, RACKS), ("slot", slot, SLOTS)):
        if value not in allowed:
            raise ConfigError(
                f"{token!r}: {what} {value} out of range"
                f" (allowed {allowed.start}..{allowed.stop - 1})"
            )
    return rack, slot


def _parse_digit(token: str, what: str, text: str, base: int, allowed: range) -> int:
    shown = f"{allowed.start:X}..{allowed.stop - 1:X}"
    if len(text) != 1:
        raise ConfigError(f"{token!r}: {what} {text} out of range (allowed {shown})")
    try:
        value = int(text, base)
    except ValueError:
        raise ConfigError(f"{token!r}: {what} {text} is not a digit (allowed {shown})") from None
    if value not in allowed:
        raise ConfigError(f"{token!r}: {what} {text} out of range (allowed {shown})")
    return value


# --- Text Block address TXTi,M = H'xyzz' ---------------------------------------------


class TxtAddress(NamedTuple):
    """A decoded ``TXTi,M``: rack, slot and zz (0x00, 0x01 or 0x63)."""

    rack: int
    slot: int
    channel: int  # the low byte: 0x00 / 0x01 a channel, 0x63 the module system

    @property
    def is_module_system(self) -> bool:
        return self.channel == TXT_MODULE_SYSTEM


def parse_txt_address(word: int) -> TxtAddress:
    """H'0563' -> (0, 5, 0x63): rack in bits F..C, slot in B..8, zz in the low byte."""
    if not 0 <= word <= 0xFFFF:
        raise ConfigError(f"TXTi,M {word} is not a 16-bit word (allowed H'0000'..H'FFFF')")
    return _checked_txt(word >> 12, (word >> 8) & 0xF, word & 0xFF, f"H'{word:04X}'")


def format_txt_address(rack: int, slot: int, zz: int) -> int:
    """(2, 3, 0x01) -> H'2301'.  zz is the byte value: the module system is 0x63."""
    _checked_txt(rack, slot, zz, f"rack {rack} slot {slot} zz 0x{zz:02X}")
    return (rack << 12) | (slot << 8) | zz


def _checked_txt(rack: int, slot: int, zz: int, shown: str) -> TxtAddress:
    if rack not in RACKS or slot not in SLOTS:
        raise ConfigError(
            f"TXTi,M {shown}: rack {rack} slot {slot} out of range (allowed rack"
            f" {RACKS.start}..{RACKS.stop - 1}, slot {SLOTS.start}..{SLOTS.stop - 1})"
        )
    if zz not in TXT_CHANNELS:
        raise ConfigError(
            f"TXTi,M {shown}: zz 0x{zz:02X} is neither a channel nor the module system"
            " (allowed 00, 01, 63 written in hex: 0x00, 0x01, 0x63)"
        )
    return TxtAddress(rack, slot, zz)
