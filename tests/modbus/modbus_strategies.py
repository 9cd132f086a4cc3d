"""Hypothesis strategies for Modbus requests and their results."""

from __future__ import annotations

from hypothesis import strategies as st

from fieldtwin.modbus.model import (
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    Result,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)

addresses = st.integers(0, 0xFFFF)
words = st.integers(0, 0xFFFF)


@st.composite
def _ranged(draw: st.DrawFn, limit: int) -> tuple[int, int]:
    count = draw(st.integers(1, limit))
    address = draw(st.integers(0, 0x10000 - count))
    return address, count


@st.composite
def read_bits(draw: st.DrawFn) -> Request:
    address, count = draw(_ranged(2000))
    return ReadBits(draw(st.sampled_from((1, 2))), address, count)


@st.composite
def read_words(draw: st.DrawFn) -> Request:
    address, count = draw(_ranged(125))
    return ReadWords(draw(st.sampled_from((3, 4))), address, count)


@st.composite
def write_bits(draw: st.DrawFn) -> Request:
    address, count = draw(_ranged(1968))
    return WriteBits(address, tuple(draw(st.lists(st.booleans(), min_size=count, max_size=count))))


@st.composite
def write_words(draw: st.DrawFn) -> Request:
    address, count = draw(_ranged(123))
    return WriteWords(address, tuple(draw(st.lists(words, min_size=count, max_size=count))))


requests: st.SearchStrategy[Request] = st.one_of(
    read_bits(),
    read_words(),
    st.builds(WriteBit, addresses, st.booleans()),
    st.builds(WriteWord, addresses, words),
    write_bits(),
    write_words(),
    st.just(ReadExceptionStatus()),
)

small_requests: st.SearchStrategy[Request] = st.one_of(
    st.builds(ReadWords, st.sampled_from((3, 4)), st.integers(0, 200), st.integers(1, 8)),
    st.builds(ReadBits, st.sampled_from((1, 2)), st.integers(0, 200), st.integers(1, 40)),
    st.builds(WriteWord, st.integers(0, 255), words),
    st.builds(WriteBit, st.integers(0, 255), st.booleans()),
    st.builds(WriteWords, st.integers(0, 200), st.lists(words, min_size=1, max_size=8).map(tuple)),
    st.builds(
        WriteBits, st.integers(0, 200), st.lists(st.booleans(), min_size=1, max_size=40).map(tuple)
    ),
    st.just(ReadExceptionStatus()),
)


@st.composite
def result_for(draw: st.DrawFn, request: Request) -> Result:
    match request:
        case ReadBits(count=n):
            return tuple(draw(st.lists(st.booleans(), min_size=n, max_size=n)))
        case ReadWords(count=n):
            return tuple(draw(st.lists(words, min_size=n, max_size=n)))
        case ReadExceptionStatus():
            return draw(st.integers(0, 255))
    return None
