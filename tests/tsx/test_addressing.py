"""PL7 object names and Text Block addresses (fieldtwin.tsx.addressing)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.addressing import (
    TXT_MODULE_SYSTEM,
    ObjectKind,
    ObjectRef,
    TxtAddress,
    format_module,
    format_object,
    format_txt_address,
    parse_module,
    parse_object,
    parse_txt_address,
)

IW, OW, IB, OB, FAULT = ObjectKind.IW, ObjectKind.OW, ObjectKind.I, ObjectKind.O, ObjectKind.FAULT


# --- every accepted form -----------------------------------------------------------


@pytest.mark.parametrize(
    ("token", "expected", "canonical"),
    [
        # AEM 1.1-1 "for a module in rack 2 and located in slot number 3: IW23,0 ... OW23,5"
        ("IW23,0", ObjectRef(IW, 2, 3, 0), "IW23,0"),
        ("OW23,5", ObjectRef(OW, 2, 3, 5), "OW23,5"),
        # rack 0 with or without its digit
        ("IW5,0", ObjectRef(IW, 0, 5, 0), "IW5,0"),
        ("IW05,0", ObjectRef(IW, 0, 5, 0), "IW5,0"),
        # AEM 4.1-1 register bits: IW5,0,C (bit C of status word 0), IW5,2,D
        ("IW5,0,C", ObjectRef(IW, 0, 5, 0, 12), "IW5,0,C"),
        ("IW5,2,D", ObjectRef(IW, 0, 5, 2, 13), "IW5,2,D"),
        ("OW5,0,C", ObjectRef(OW, 0, 5, 0, 12), "OW5,0,C"),
        ("OW4,1,1", ObjectRef(OW, 0, 4, 1, 1), "OW4,1,1"),  # DEM 5.3-4 purge
        ("IW77,7,F", ObjectRef(IW, 7, 7, 7, 15), "IW77,7,F"),
        # discrete bits, hex index (AEM 2.4-2 Ixy,0..Ixy,F; SCM 3.4 I14,F)
        ("I14,F", ObjectRef(IB, 1, 4, 15), "I14,F"),
        ("O17,4", ObjectRef(OB, 1, 7, 4), "O17,4"),
        ("O7,0", ObjectRef(OB, 0, 7, 0), "O7,0"),
        ("I2,A", ObjectRef(IB, 0, 2, 10), "I2,A"),
        # AEM 2.4-2 module fault bit Ixy,S
        ("I5,S", ObjectRef(FAULT, 0, 5), "I5,S"),
        ("I23,S", ObjectRef(FAULT, 2, 3), "I23,S"),
        # case-insensitive, surrounding and inner blanks (AEM 5.2 prints "O 6,0")
        ("iw5,0,c", ObjectRef(IW, 0, 5, 0, 12), "IW5,0,C"),
        ("i5,s", ObjectRef(FAULT, 0, 5), "I5,S"),
        ("  Ow23,1,a ", ObjectRef(OW, 2, 3, 1, 10), "OW23,1,A"),
        ("O 6,0", ObjectRef(OB, 0, 6, 0), "O6,0"),
        ("IW5, 3", ObjectRef(IW, 0, 5, 3), "IW5,3"),
        ("I05,S", ObjectRef(FAULT, 0, 5), "I5,S"),
    ],
)
def test_parse_and_format(token: str, expected: ObjectRef, canonical: str) -> None:
    ref = parse_object(token)
    assert ref == expected
    assert format_object(ref) == canonical
    assert str(ref) == canonical


@pytest.mark.parametrize(
    ("token", "is_bit", "is_output"),
    [
        ("IW5,0", False, False),
        ("OW5,0", False, True),
        ("IW5,0,3", True, False),
        ("OW5,0,3", True, True),
        ("I5,3", True, False),
        ("O5,3", True, True),
        ("I5,S", True, False),
    ],
)
def test_is_bit_and_is_output(token: str, is_bit: bool, is_output: bool) -> None:
    ref = parse_object(token)
    assert ref.is_bit is is_bit
    assert ref.is_word is (not is_bit)
    assert ref.is_output is is_output


def test_word_of_a_register_bit_and_module() -> None:
    ref = parse_object("OW23,1,8")
    assert ref.word() == parse_object("OW23,1")
    assert ref.module == (2, 3)
    with pytest.raises(ConfigError, match="not a register word"):
        parse_object("I5,3").word()


@pytest.mark.parametrize(
    ("token", "module"), [("5", (0, 5)), ("05", (0, 5)), ("23", (2, 3)), (" 77 ", (7, 7))]
)
def test_parse_module(token: str, module: tuple[int, int]) -> None:
    assert parse_module(token) == module
    assert parse_module(format_module(*module)) == module


@pytest.mark.parametrize(
    ("token", "message"),
    [
        ("", "not a module address"),
        ("x5", "not a module address"),
        ("-5", "not a module address"),
        ("123", "is not rack and slot"),
        ("8", "slot 8 out of range"),
        ("95", "rack 9 out of range"),
    ],
)
def test_parse_module_rejects(token: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_module(token)


# --- every rejected form -------------------------------------------------------------


@pytest.mark.parametrize(
    ("token", "message"),
    [
        ("IW5,9", "'IW5,9': word index 9 out of range (allowed 0..7)"),
        ("IW5,8,0", "word index 8 out of range (allowed 0..7)"),
        ("OW5,A", "word index A is not a digit (allowed 0..7)"),
        ("IW5,10", "word index 10 out of range (allowed 0..7)"),
        ("IW5,S", "word index S is not a digit"),
        ("IW5,0,G", "bit G is not a digit (allowed 0..F)"),
        ("IW5,0,10", "bit 10 out of range (allowed 0..F)"),
        ("I5,G", "bit G is not a digit (allowed 0..F)"),
        ("I5,10", "bit 10 out of range (allowed 0..F)"),
        ("I5,0,1", "a discrete bit takes no second index"),
        ("I5,S,1", "a discrete bit takes no second index"),
        ("O5,S", "only inputs have a fault bit"),
        ("IW8,0", "slot 8 out of range (allowed 0..7)"),
        ("IW58,0", "slot 8 out of range (allowed 0..7)"),
        ("IW85,0", "rack 8 out of range (allowed 0..7)"),
        ("IW123,0", "module address '123' is not rack and slot"),
        (
            "QW5,0",
            "unknown object (allowed IWxy,i  OWxy,i  IWxy,i,j  OWxy,i,j  Ixy,i  Oxy,i  Ixy,S)",
        ),
        ("IW5", "unknown object"),
        ("IW,0", "unknown object"),
        ("W5,0", "unknown object"),
        ("IW5,0,", "unknown object"),
        ("", "unknown object"),
        ("IWA,0", "unknown object"),
        ("IW5;0", "unknown object"),
        ("IW-5,0", "unknown object"),
    ],
)
def test_rejected_forms(token: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_object(token)
    text = str(info.value)
    assert text.startswith(repr(token))
    assert message in text


@pytest.mark.parametrize(
    "args",
    [
        (IW, 0, 5, None, None),
        (IW, 0, 5, 8, None),
        (OW, 0, 5, 0, 16),
        (IB, 0, 5, 16, None),
        (IB, 0, 5, 1, 2),
        (FAULT, 0, 5, 0, None),
        (OB, 8, 0, 0, None),
        (OB, 0, -1, 0, None),
    ],
)
def test_object_ref_validates_itself(args: tuple[ObjectKind, int, int, int, int]) -> None:
    with pytest.raises(ConfigError):
        ObjectRef(*args)


# --- properties ----------------------------------------------------------------------

racks = st.integers(0, 7)
slots = st.integers(0, 7)


@st.composite
def object_refs(draw: st.DrawFn) -> ObjectRef:
    kind = draw(st.sampled_from(ObjectKind))
    rack, slot = draw(racks), draw(slots)
    if kind in (IW, OW):
        return ObjectRef(
            kind, rack, slot, draw(st.integers(0, 7)), draw(st.none() | st.integers(0, 15))
        )
    if kind is FAULT:
        return ObjectRef(kind, rack, slot)
    return ObjectRef(kind, rack, slot, draw(st.integers(0, 15)))


@given(object_refs())
def test_format_parse_round_trip(ref: ObjectRef) -> None:
    text = format_object(ref)
    assert parse_object(text) == ref
    assert text == text.upper()
    assert parse_object(text.lower()) == ref


@given(object_refs())
def test_rack_zero_digit_is_optional(ref: ObjectRef) -> None:
    text = format_object(ref)
    letters = "I" if ref.kind is FAULT else ref.kind.value
    tail = text[text.index(",") :]
    assert parse_object(f"{letters}{ref.rack}{ref.slot}{tail}") == ref
    if ref.rack == 0:
        assert text.startswith(f"{letters}{ref.slot},")


@given(st.text(max_size=12))
def test_parse_never_fails_otherwise(token: str) -> None:
    try:
        ref = parse_object(token)
    except ConfigError as exc:
        assert str(exc).startswith(repr(token))
    else:
        assert parse_object(format_object(ref)) == ref


# --- Text Block address TXTi,M = H'xyzz' -----------------------------------------------


@pytest.mark.parametrize(
    ("word", "expected"),
    [
        (0x0563, (0, 5, TXT_MODULE_SYSTEM)),  # AEM 3.5-2 "H'563: slot 5 of rack 0"
        (0x0163, (0, 1, 0x63)),  # AEM 5.2 TXT0 configuration H'0163'
        (0x0100, (0, 1, 0x00)),  # AEM 5.2 TXT1 thresholds H'0100'
        (0x0700, (0, 7, 0x00)),  # SCM 3 configuration example: channel 0, rack 0 slot 7
        (0x0263, (0, 2, 0x63)),  # SCM 6.3 additional requests "TXTi,M = H'0263'"
        (0x0701, (0, 7, 0x01)),
        (0x2301, (2, 3, 0x01)),
        (0x7763, (7, 7, 0x63)),
    ],
)
def test_txt_address_vectors(word: int, expected: tuple[int, int, int]) -> None:
    address = parse_txt_address(word)
    assert address == expected
    assert isinstance(address, TxtAddress)
    assert address.is_module_system is (expected[2] == 0x63)
    assert format_txt_address(*expected) == word


@pytest.mark.parametrize(
    ("word", "message"),
    [
        (0x0502, "zz 0x02 is neither a channel nor the module system"),
        (0x053F, "zz 0x3F"),  # decimal 63 is not the module system: 0x63 is
        (0x0863, "rack 0 slot 8 out of range"),
        (0x8063, "rack 8 slot 0 out of range"),
        (0x10000, "not a 16-bit word"),
        (-1, "not a 16-bit word"),
    ],
)
def test_txt_address_rejected(word: int, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_txt_address(word)


def test_format_txt_address_rejects_decimal_63() -> None:
    with pytest.raises(ConfigError, match="allowed 00, 01, 63 written in hex"):
        format_txt_address(0, 5, 63)


@given(racks, slots, st.sampled_from([0x00, 0x01, 0x63]))
def test_txt_address_round_trip(rack: int, slot: int, zz: int) -> None:
    word = format_txt_address(rack, slot, zz)
    assert f"{word:04X}" == f"{rack}{slot}{zz:02X}"  # the digits read like the name
    assert parse_txt_address(word) == (rack, slot, zz)


@given(st.integers(0, 0xFFFF))
def test_txt_address_any_word(word: int) -> None:
    try:
        address = parse_txt_address(word)
    except ConfigError as exc:
        assert f"H'{word:04X}'" in str(exc)
    else:
        assert format_txt_address(*address) == word
