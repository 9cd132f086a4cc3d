"""Shared helpers for the TES tests: a master's requests through execute()."""

from __future__ import annotations

from fieldtwin.modbus.model import (
    Link,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Result,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)
from fieldtwin.tes import Tes


def read_words(tes: Tes, address: int, count: int = 1, link: Link = Link.RS485) -> Result:
    return tes.execute(ReadWords(3, address, count), link, tes.clock.now, False)


def read_word(tes: Tes, address: int) -> int:
    result = read_words(tes, address)
    assert isinstance(result, tuple), result
    value = result[0]
    assert isinstance(value, int)
    return value


def write_word(tes: Tes, address: int, value: int, link: Link = Link.RS485) -> Result:
    return tes.execute(WriteWord(address, value), link, tes.clock.now, False)


def write_words(tes: Tes, address: int, values: tuple[int, ...]) -> Result:
    return tes.execute(WriteWords(address, values), Link.RS485, tes.clock.now, False)


def read_bits(tes: Tes, address: int, count: int, function: int = 1) -> Result:
    return tes.execute(ReadBits(function, address, count), Link.RS485, tes.clock.now, False)


def write_bit(tes: Tes, address: int, value: bool) -> Result:
    return tes.execute(WriteBit(address, value), Link.RS485, tes.clock.now, False)


def write_bits(tes: Tes, address: int, values: tuple[bool, ...]) -> Result:
    return tes.execute(WriteBits(address, values), Link.RS485, tes.clock.now, False)


def quick_status(tes: Tes) -> Result:
    return tes.execute(ReadExceptionStatus(), Link.RS485, tes.clock.now, False)


def pair(tes: Tes, high_address: int) -> int:
    """A 32-bit value from its high part / low part words."""
    return (read_word(tes, high_address) << 16) | read_word(tes, high_address + 1)
