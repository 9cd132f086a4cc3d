"""The pcap writer's Internet checksum (one big number modulo 0xFFFF) is RFC 1071's
word-by-word sum, for any bytes: odd lengths, all zeros, and the words whose sum is
a multiple of 0xFFFF (the one's complement sum's two zeros)."""

from __future__ import annotations

import os

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.runtime.pcap import _checksum, checksum_reference

EXAMPLES = 200 if os.environ.get("FIELDTWIN_FAST_EXAMPLES") else 2000

words = st.lists(st.sampled_from([0, 1, 0xFFFF, 0xFFFE, 0x8000, 0x7FFF]) | st.integers(0, 0xFFFF))


@settings(max_examples=EXAMPLES, deadline=None)
@given(
    data=st.binary(max_size=400) | words.map(lambda w: b"".join(x.to_bytes(2, "big") for x in w))
)
def test_the_checksum_is_rfc_1071s(data: bytes) -> None:
    assert _checksum(data) == checksum_reference(data)


def test_the_two_zeros() -> None:
    for data in (
        b"",
        b"\x00",
        b"\x00\x00\x00",
        b"\xff\xff",
        b"\xff\xfe\x00\x01",
        b"\x80\x00\x7f\xff",
    ):
        assert _checksum(data) == checksum_reference(data), data
