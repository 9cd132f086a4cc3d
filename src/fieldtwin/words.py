"""16-bit words as the TSX manuals write them.

Signed/unsigned views, bits, BCD, bytes <-> words (1st character in the low
byte, as every Text Block table of the manuals shows) and the ``H'00A0'``
notation (the SCM manual's ``B'0802'`` is read the same way: AMB-SCM-01).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

from fieldtwin.errors import ConfigError

WORD_MASK = 0xFFFF


def to_unsigned(value: int) -> int:
    """-32768..65535 -> 0..65535 (two's complement for negatives)."""
    if not -0x8000 <= value <= WORD_MASK:
        raise ConfigError(f"{value} does not fit a 16-bit word (allowed -32768..65535)")
    return value & WORD_MASK


def to_signed(value: int) -> int:
    """0..65535 -> -32768..32767."""
    value &= WORD_MASK
    return value - 0x10000 if value & 0x8000 else value


def get_bit(word: int, bit: int) -> int:
    _check_bit(bit)
    return (word >> bit) & 1


def set_bit(word: int, bit: int, value: bool | int) -> int:
    _check_bit(bit)
    word &= WORD_MASK
    return (word | (1 << bit)) if value else (word & ~(1 << bit))


def _check_bit(bit: int) -> None:
    if not 0 <= bit <= 15:
        raise ConfigError(f"bit {bit} is not in a 16-bit word (allowed 0..F)")


def bits_to_word(bits: Iterable[bool | int]) -> int:
    """Bit 0 first."""
    word = 0
    for i, b in enumerate(bits):
        if b:
            word |= 1 << i
    return word & WORD_MASK


def nibble(word: int, index: int) -> int:
    """The manuals' "4-bit bytes": index 0 is bits 3..0 (the "first")."""
    return (word >> (4 * index)) & 0xF


# --- BCD -------------------------------------------------------------------


def bcd_decode(word: int, *, field: str = "value") -> int:
    """H'9600' -> 9600.  A nibble above 9 raises ConfigError naming the field.

    Devices that answer a non-BCD table with a report use :func:`is_bcd` first.
    """
    word &= WORD_MASK
    result = 0
    for index in range(3, -1, -1):
        digit = nibble(word, index)
        if digit > 9:
            raise ConfigError(
                f"{field}: {format_hex(word)} is not BCD (digit {digit:X} at nibble {index};"
                " each nibble must be 0..9)"
            )
        result = result * 10 + digit
    return result


def is_bcd(word: int) -> bool:
    return all(nibble(word & WORD_MASK, i) <= 9 for i in range(4))


def bcd_encode(value: int) -> int:
    """9600 -> H'9600' (0..9999)."""
    if not 0 <= value <= 9999:
        raise ConfigError(f"{value} cannot be written in 4 BCD digits (allowed 0..9999)")
    word = 0
    for shift in range(0, 16, 4):
        word |= (value % 10) << shift
        value //= 10
    return word


# --- bytes <-> words -------------------------------------------------------


def bytes_to_words(data: bytes | bytearray | Sequence[int]) -> list[int]:
    """1st character in the low byte; an odd count pads the last high byte with 0."""
    raw = bytes(data)
    if len(raw) % 2:
        raw += b"\x00"
    return [raw[i] | (raw[i + 1] << 8) for i in range(0, len(raw), 2)]


def words_to_bytes(words: Iterable[int], length: int | None = None) -> bytes:
    """Low byte first; ``length`` keeps only that many bytes."""
    out = bytearray()
    for word in words:
        w = to_unsigned(word)
        out.append(w & 0xFF)
        out.append(w >> 8)
    if length is not None:
        if not 0 <= length <= len(out):
            raise ConfigError(f"{length} bytes asked from {len(out)} bytes of words")
        del out[length:]
    return bytes(out)


# --- H'00A0' ---------------------------------------------------------------

# The manual renderings often print the quote as a typographic one: H’563 (AEM 3.5-2).
_HEX_RE = re.compile(r"^[HB]['’]([0-9A-F]{1,4})['’]?$", re.IGNORECASE)


def parse_word(token: str) -> int:
    """``H'00A0'``, ``h'a0'``, ``H’563``, ``B'0802'``, ``0x00A0``, ``-5`` or ``160`` -> 0..65535."""
    text = token.strip()
    match = _HEX_RE.match(text)
    if match:
        return int(match.group(1), 16)
    try:
        value = int(text, 0) if text.lower().startswith(("0x", "-0x")) else int(text, 10)
    except ValueError:
        raise ConfigError(
            f"{token!r} is not a word value (allowed H'0000'..H'FFFF', 0x0..0xFFFF, -32768..65535)"
        ) from None
    return to_unsigned(value)


def plant_word(value: object, where: str) -> int:
    """A word as a plant file gives it (``"H'0802'"`` or 0..65535); ConfigError naming ``where``."""
    if isinstance(value, str):
        try:
            return parse_word(value)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFFFF:
        raise ConfigError(f"{where}: {value!r} is not a word (0..65535 or \"H'0014'\")")
    return value


def format_hex(word: int, digits: int = 4) -> str:
    """160 -> ``H'00A0'``."""
    return f"H'{word & ((1 << (4 * digits)) - 1):0{digits}X}'"
