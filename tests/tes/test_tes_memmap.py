"""§6: every documented word of every model, read and (where writable) written."""

from __future__ import annotations

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import ExceptionCode
from fieldtwin.tes import MODELS, Tes
from fieldtwin.tes.memmap import Access, Register, history_start, memory_map
from fieldtwin.tes.models import model_named

from .helpers import read_word, read_words, write_word

# Words whose read-back differs from what was written, by design.
SPECIAL = {"status", "command"}


def _check_word(tes: Tes, reg: Register) -> str | None:
    """Read ``reg``; write it if writable; return a problem or None."""
    if not isinstance(read_word(tes, reg.address), int):
        return "read failed"
    value = 0x0A05 if reg.kind == "command" else 0x1234
    result = write_word(tes, reg.address, value)
    if not reg.access.writable:
        return None if result is ExceptionCode.ILLEGAL_DATA_ADDRESS else f"write gave {result}"
    if result is not None:
        return f"write refused: {result}"
    if reg.kind == "status":
        return None
    expected = value if reg.fitted else 0  # §6.4.5 analog command keeps bits 11-08, 03-00
    got = read_word(tes, reg.address)
    return None if got == expected else f"read back {got:#x}, expected {expected:#x}"


@pytest.mark.parametrize("model", list(MODELS))
def test_every_documented_word_reads_and_writes(model: str) -> None:
    tes = Tes(model)
    problems = {}
    for reg in memory_map(tes.model):
        problem = _check_word(tes, reg)
        if problem:
            problems[f"{reg.address:03X}h {reg.name}"] = problem
    assert problems == {}
    assert len(memory_map(tes.model)) > 30


@pytest.mark.parametrize("model", list(MODELS))
def test_the_word_after_the_map_is_exception_2(model: str) -> None:
    tes = Tes(model)
    last = max(memory_map(tes.model), key=lambda r: r.address).address
    assert read_words(tes, last + 1) is ExceptionCode.ILLEGAL_DATA_ADDRESS
    assert read_words(tes, last, 2) is ExceptionCode.ILLEGAL_DATA_ADDRESS
    assert isinstance(read_words(tes, last), tuple)


def _addr(model: str, name: str) -> int:
    regs = {r.name: r.address for r in memory_map(MODELS[model])}
    return regs[name]


@pytest.mark.parametrize(
    ("model", "name", "address"),
    [
        # §6.2.2
        ("TES 16EST", "memorized[1]", 0x002),
        ("TES 32EST", "filter_1", 0x00B),
        ("TES 32EST", "command[1]", 0x00D),
        ("TES 32EST", "blink[1].off", 0x011),
        # §6.2.3
        ("TES 32ET", "watchdog", 0x016),
        ("TES 32ET", "rs485.exception_replies", 0x017),
        ("TES 32ET", "rs485.no_silence", 0x01D),
        ("TES 32ET", "rs232.no_silence", 0x024),
        # §6.2.4 - 6.2.6 (labels of the manual)
        ("TES 16EST", "counter_rise[7].high", 0x033),
        ("TES 32EST", "counter_rise[16].low", 0x046),
        ("TES 32ET", "counter_rise[31].high", 0x063),
        ("TES 32ET", "counter_fall[31].low", 0x0A4),
        ("TES 16EST", "duration_1[8].high", 0x0B5),
        ("TES 32ET", "duration_1[31].low", 0x0E4),
        ("TES 32EST", "duration_0[15].high", 0x103),
        ("TES 32ET", "duration_0[31].high", 0x123),
        ("TES 32ET", "cumulated_1[31].low", 0x164),
        ("TES 32ET", "cumulated_0[31].low", 0x1A4),
        # §6.2.7
        ("TES 32ET-S", "short_circuit[1]", 0x1A6),
        ("TES 32ET-S", "defaults[1]", 0x1AA),
        ("TES 32ET-S", "connection[1]", 0x1AC),
        # §6.3
        ("TES 32ST", "command[1]", 0x006),
        ("TES 32ST", "blink[1].off", 0x00A),
        ("TES 32ST", "and_mask[1].high", 0x015),
        ("TES 32ST", "watchdog", 0x016),
        ("TES 32ST", "rs232.no_silence", 0x024),
        # §6.4
        ("TES 8EA", "analog_input[7]", 0x00A),
        ("TES 8EA", "channel_state[7]", 0x012),
        ("TES 8ESA", "analog_output[7]", 0x01B),
        ("TES 8EA", "threshold_polarity", 0x03B),
        ("TES 8EA", "fallback_enable", 0x046),
        ("TES 8EA", "rs232.no_silence", 0x054),
        ("TES 8EA", "storage_period", 0x055),
        ("TES 8EA", "history[0][0]", 87),
        ("TES 8EA", "history[0][119]", 206),
        ("TES 8EA", "reserved_0CF", 207),
        ("TES 8EA", "history[5][0]", 692),  # AMB-TES-14: 2B4h, the manual's "264h" is a typo
        ("TES 8EA", "history[7][119]", 1053),
        ("TES 8EA", "counter_rise[0].high", 0x41F),
        ("TES 8EA", "counter_fall[3].low", 0x42E),
        ("TES 8EA", "duration_0[3].low", 0x43E),
        ("TES 8EA", "cumulated_1[0].high", 0x43F),
        ("TES 8EA", "cumulated_0[3].low", 0x44E),
    ],
)
def test_section_6_addresses(model: str, name: str, address: int) -> None:
    assert _addr(model, name) == address


def test_section_6_4_13_history_blocks_follow_the_decimals() -> None:
    assert [history_start(k) for k in range(8)] == [87, 208, 329, 450, 571, 692, 813, 934]


@pytest.mark.parametrize("model", list(MODELS))
def test_maps_have_no_duplicate_address(model: str) -> None:
    regs = memory_map(MODELS[model])
    assert len({r.address for r in regs}) == len(regs)


def test_map_sizes_per_family() -> None:
    assert max(r.address for r in memory_map(MODELS["TES 32ET"])) == 0x1A4
    assert max(r.address for r in memory_map(MODELS["TES 32ET-S"])) == 0x1AC
    assert max(r.address for r in memory_map(MODELS["TES 32ST"])) == 0x024
    assert max(r.address for r in memory_map(MODELS["TES 4SA"])) == 0x44E


def test_mp_words_are_marked() -> None:
    regs = {r.address: r for r in memory_map(MODELS["TES 32EST"])}
    assert regs[0x00C].access is Access.RW and regs[0x00D].access is Access.MP
    assert regs[0x016].access is Access.MP and regs[0x005].access is Access.R


@pytest.mark.parametrize("name", ["TES 8EA", "8ea", "tes 16 est", "TES_32ET-S", "32st"])
def test_model_names(name: str) -> None:
    assert model_named(name).name in MODELS


def test_unknown_model_lists_the_models() -> None:
    with pytest.raises(ConfigError, match=r"unknown TES model 'TES 99'.*TES 16EST.*TES 8SA-U"):
        Tes("TES 99")


@pytest.mark.parametrize(
    ("model", "di", "do", "ai", "ao"),
    [
        ("TES 16EST", 8, 8, (), ()),
        ("TES 32EST", 16, 16, (), ()),
        ("TES 32ET", 32, 0, (), ()),
        ("TES 32ET-S", 32, 0, (), ()),
        ("TES 32ST", 0, 32, (), ()),
        ("TES 4EA", 4, 4, (0, 1, 2, 3), ()),
        ("TES 4SA", 4, 4, (), (0, 1, 2, 3)),
        ("TES 8EA", 4, 4, tuple(range(8)), ()),
        ("TES 8ESA", 4, 4, (0, 1, 2, 3), (4, 5, 6, 7)),
        ("TES 8SA-U", 4, 4, (), tuple(range(8))),
    ],
)
def test_model_io_counts(
    model: str, di: int, do: int, ai: tuple[int, ...], ao: tuple[int, ...]
) -> None:
    m = MODELS[model]
    assert (m.digital_inputs, m.digital_outputs, m.analog_inputs, m.analog_outputs) == (
        di,
        do,
        ai,
        ao,
    )
