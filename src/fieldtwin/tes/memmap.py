"""The memory maps of section 6, as data: one Register per documented word.

Every word carries its address, a name, its access (R read only, RW read and
write, MP a parameter word loaded from the EEPROM at each power-on) and the
manual's meaning.  ``kind`` (a :class:`fieldtwin.tes.kinds.Kind`) and
``index`` tell the device which behaviour answers it (``COUNTER_RISE`` word 7 is
the low part of input 3's counter, ...).  A model's map is built once and
shared by every TES of that model (``register_table``).
"""

from __future__ import annotations

import enum
import functools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from types import MappingProxyType

from fieldtwin.tes.kinds import Kind
from fieldtwin.tes.models import Family, TesModel


class Access(enum.Enum):
    R = "R"  # read only: a write is answered with exception 2
    RW = "RW"
    MP = "MP"  # "Memory Parameters" (§6.1 glossary): RW, loaded from EEPROM at power-on

    @property
    def writable(self) -> bool:
        return self is not Access.R


@dataclass(frozen=True, slots=True)
class Register:
    address: int
    name: str
    access: Access
    meaning: str
    kind: Kind
    index: int = 0
    fitted: bool = True  # False: a channel the model lacks (reads 0, writes are ignored)


R, RW, MP = Access.R, Access.RW, Access.MP

_LINK_COUNTERS = (
    "exception_replies",
    "not_ready_replies",
    "frames_executed",
    "crc_errors",
    "wrong_characters",
    "good_frames",
    "no_silence",
)
_LINK_MEANINGS = (
    "number of exception replies returned by TES",
    "number of replies « slave not ready » returned by TES",
    "number of frames correctly executed by TES",
    "number of received frames with CRC16 errors",
    "number of wrong characters received by TES",
    "number of received frames without errors",
    "not analysed frames by default of silent time",
)


def _link_counters(start: int, link: str) -> Iterator[Register]:
    # §6.2.3.2 / 6.3.4-5 / 6.4.12 diagnosis counters, 7 words per link
    for i, (name, meaning) in enumerate(zip(_LINK_COUNTERS, _LINK_MEANINGS, strict=True)):
        yield Register(
            start + i, f"{link}.{name}", RW, f"{link.upper()}: {meaning}", Kind(f"diag_{link}"), i
        )


def _pairs(start: int, count: int, kind: Kind, label: str, fitted: int) -> Iterator[Register]:
    """32-bit values as high part / low part word pairs (§6.2.4, 6.2.5, 6.4.14)."""
    for i in range(count):
        ok = i < fitted
        note = "" if ok else " (input not fitted on this model: reads 0)"
        for half, part in ((0, "high"), (1, "low")):
            yield Register(
                start + 2 * i + half,
                f"{kind.value}[{i}].{part}",
                RW,
                f"{label} input No {i}, {part} part{note}",
                kind,
                2 * i + half,
                ok,
            )


def _digital_inputs_map(model: TesModel) -> Iterator[Register]:
    # §6.2.1 - 6.2.2
    yield Register(
        0x000,
        "status",
        RW,
        "TES general word (bits 0..2 reset by master, bit 3 by TES)",
        Kind.STATUS,
    )
    yield Register(0x001, "memorized[0]", R, "memorized inputs [15..00]", Kind.MEMORIZED, 0)
    yield Register(0x002, "memorized[1]", R, "memorized inputs [31..16]", Kind.MEMORIZED, 1)
    yield Register(0x003, "filtered[0]", R, "filtered inputs [15..00]", Kind.FILTERED, 0)
    yield Register(0x004, "filtered[1]", R, "filtered inputs [31..16]", Kind.FILTERED, 1)
    yield Register(0x005, "direct[0]", R, "directs inputs [15..00]", Kind.DIRECT, 0)
    yield Register(0x006, "direct[1]", R, "directs inputs [31..16]", Kind.DIRECT, 1)
    yield Register(0x007, "outputs[0]", R, "outputs instantaneous state [15..00]", Kind.OUTPUTS, 0)
    yield Register(0x008, "reserved_008", R, "Reserved", Kind.ZERO)
    yield Register(0x009, "reserved_009", R, "Reserved", Kind.ZERO)
    yield Register(
        0x00A, "filter_0", MP, "filters duration for inputs state 0 (Tb=5ms)", Kind.FILTER, 0
    )
    yield Register(
        0x00B, "filter_1", MP, "filters duration for inputs state 1 (Tb=5ms)", Kind.FILTER, 1
    )
    yield Register(
        0x00C,
        "command[0]",
        RW,
        "word 0 of output command: choice of blinking outputs",
        Kind.BLINK_SELECT,
        0,
    )
    yield Register(
        0x00D,
        "command[1]",
        MP,
        "word 1 of output command: fixed states 0/1 or frequency",
        Kind.COMMAND,
        0,
    )
    yield from _blink_words(0x00E)
    # §6.2.3.1 master activity and fallback
    yield Register(0x012, "or_mask[0]", MP, "OR mask of word 0 of output command", Kind.MASK, 0)
    yield Register(0x013, "or_mask[1]", MP, "OR mask of word 1 of output command", Kind.MASK, 1)
    yield Register(0x014, "and_mask[0]", MP, "AND mask of word 0 of output command", Kind.MASK, 2)
    yield Register(0x015, "and_mask[1]", MP, "AND mask of word 1 of output command", Kind.MASK, 3)
    yield Register(
        0x016,
        "watchdog",
        MP,
        "maximum duration separating 2 master requests (Tb=100ms)",
        Kind.WATCHDOG,
    )
    yield from _link_counters(0x017, "rs485")
    yield from _link_counters(0x01E, "rs232")
    n = model.digital_inputs
    yield from _pairs(0x025, 32, Kind.COUNTER_RISE, "counter of rising edge", n)
    yield from _pairs(0x065, 32, Kind.COUNTER_FALL, "counter of falling edge", n)
    yield from _pairs(0x0A5, 32, Kind.DURATION_1, "duration of state 1 (Tb=100ms) for", n)
    yield from _pairs(0x0E5, 32, Kind.DURATION_0, "duration of state 0 (Tb=100ms) for", n)
    yield from _pairs(
        0x125, 32, Kind.CUMULATED_1, "cumulated duration of states 1 (Tb=100ms) for", n
    )
    yield from _pairs(
        0x165, 32, Kind.CUMULATED_0, "cumulated duration of states 0 (Tb=100ms) for", n
    )
    if model.safety:
        yield from _safety_words()


def _safety_words() -> Iterator[Register]:
    # §6.2.7 TES 32ET-S broken wires and short circuit detection
    yield Register(
        0x1A5, "short_circuit[0]", R, "SC inputs E1 to E16 (bit i -> E(i+1))", Kind.SC, 0
    )
    yield Register(0x1A6, "short_circuit[1]", R, "SC inputs E17 to E32", Kind.SC, 1)
    yield Register(0x1A7, "open_circuit[0]", R, "OC inputs E1 to E16", Kind.OC, 0)
    yield Register(0x1A8, "open_circuit[1]", R, "OC inputs E17 to E32", Kind.OC, 1)
    yield Register(0x1A9, "defaults[0]", R, "defaults OC or SC E1 to E16", Kind.FAULT, 0)
    yield Register(0x1AA, "defaults[1]", R, "defaults OC or SC E17 to E32", Kind.FAULT, 1)
    yield Register(
        0x1AB,
        "connection[0]",
        MP,
        "connection bits E1 to E16: 1 = wired in security mode",
        Kind.CONNECTION,
        0,
    )
    yield Register(
        0x1AC,
        "connection[1]",
        MP,
        "connection bits E17 to E32: 1 = wired in security mode",
        Kind.CONNECTION,
        1,
    )


def _blink_words(start: int) -> Iterator[Register]:
    # §4.1.6 two blinking frequencies (mode 0 = A = "1", mode 1 = B = "2": AMB-TES-27)
    yield Register(
        start, "blink[0].on", MP, "duration of state 1 blinking mode 0 (Tb=5ms)", Kind.BLINK, 0
    )
    yield Register(
        start + 1, "blink[0].off", MP, "duration of state 0 blinking mode 0 (Tb=5ms)", Kind.BLINK, 1
    )
    yield Register(
        start + 2, "blink[1].on", MP, "duration of state 1 blinking mode 1 (Tb=5ms)", Kind.BLINK, 2
    )
    yield Register(
        start + 3, "blink[1].off", MP, "duration of state 0 blinking mode 1 (Tb=5ms)", Kind.BLINK, 3
    )


def _digital_outputs_map() -> Iterator[Register]:
    # §6.3 TES 32 ST
    yield Register(
        0x000, "status", RW, "TES status (bit 0 init, bit 1 fallback; reset by master)", Kind.STATUS
    )
    yield Register(0x001, "outputs[0]", R, "instantaneous outputs state [15..00]", Kind.OUTPUTS, 0)
    yield Register(0x002, "outputs[1]", R, "instantaneous outputs state [31..16]", Kind.OUTPUTS, 1)
    yield Register(
        0x003,
        "blink_select[0]",
        RW,
        "Select Fix or Blinking for outputs 0 to 15",
        Kind.BLINK_SELECT,
        0,
    )
    yield Register(
        0x004,
        "blink_select[1]",
        RW,
        "Select Fix or Blinking for outputs 16 to 31",
        Kind.BLINK_SELECT,
        1,
    )
    yield Register(
        0x005, "command[0]", RW, "Command state or outputs frequency 0 to 15", Kind.COMMAND, 0
    )
    yield Register(
        0x006, "command[1]", RW, "Command state or outputs frequency 16 to 31", Kind.COMMAND, 1
    )
    yield from _blink_words(0x007)
    for a in (0x00B, 0x00C, 0x00D):
        yield Register(a, f"not_used_{a:03X}", R, "not used", Kind.ZERO)
    masks = ("OR mask of word 0", "OR mask of word 1", "AND mask of word 0", "AND mask of word 1")
    for i in range(8):
        half = "[15..00]" if i % 2 == 0 else "[31..16]"
        name = f"{'or' if i < 4 else 'and'}_mask[{(i // 2) % 2}].{'low' if i % 2 == 0 else 'high'}"
        yield Register(
            0x00E + i, name, MP, f"{masks[i // 2]} of output command {half}", Kind.MASK, i
        )
    yield Register(
        0x016,
        "watchdog",
        MP,
        "maximum duration separating 2 master requests (Tb=100ms)",
        Kind.WATCHDOG,
    )
    yield from _link_counters(0x017, "rs485")
    yield from _link_counters(0x01E, "rs232")


HISTORY_LENGTH = 120


def history_start(channel: int) -> int:
    """§6.4.13: 120 values of input k from 87 + 121 k (decimals trusted: AMB-TES-14)."""
    return 87 + 121 * channel


def _analog_map(model: TesModel) -> Iterator[Register]:
    yield from _analog_io_words(model)
    yield from _analog_parameter_words(model)
    yield from _link_counters(0x047, "rs485")
    yield from _link_counters(0x04E, "rs232")
    yield Register(
        0x055, "storage_period", MP, "storage period: analog inputs (Tb=1s)", Kind.STORAGE_PERIOD
    )
    yield Register(0x056, "reserved_056", R, "Reserved", Kind.ZERO)
    for k in range(8):
        start = history_start(k)
        note = "" if k in model.analog_inputs else " (no analog input on this model: reads 0)"
        for j in range(HISTORY_LENGTH):
            yield Register(
                start + j,
                f"history[{k}][{j}]",
                R,
                f"120 last values of analog input No {k}, value {j} (0 = newest){note}",
                Kind.HISTORY,
                k * HISTORY_LENGTH + j,
            )
        yield Register(
            start + HISTORY_LENGTH,
            f"reserved_{start + HISTORY_LENGTH:03X}",
            R,
            "Reserved",
            Kind.ZERO,
        )
    yield from _pairs(0x41F, 4, Kind.COUNTER_RISE, "counter of rising edge", 4)
    yield from _pairs(0x427, 4, Kind.COUNTER_FALL, "counter of falling edge", 4)
    yield from _pairs(0x42F, 4, Kind.DURATION_1, "duration of state 1 (Tb=100ms) for", 4)
    yield from _pairs(0x437, 4, Kind.DURATION_0, "duration of state 0 (Tb=100ms) for", 4)
    yield from _pairs(
        0x43F, 4, Kind.CUMULATED_1, "cumulated duration of states 1 (Tb=100ms) for", 4
    )
    yield from _pairs(
        0x447, 4, Kind.CUMULATED_0, "cumulated duration of states 0 (Tb=100ms) for", 4
    )


def _analog_io_words(model: TesModel) -> Iterator[Register]:
    # §6.4.1 - 6.4.6
    yield Register(
        0x000,
        "status",
        RW,
        "TES status (bits 0, 1, 6, 7 reset by master; bit 3 by TES)",
        Kind.STATUS,
    )
    yield Register(0x001, "filtered[0]", R, "digital filtered inputs [3..0]", Kind.FILTERED, 0)
    yield Register(0x002, "memorized[0]", R, "digital stored inputs [3..0]", Kind.MEMORIZED, 0)
    for k in range(8):
        note = "" if k in model.analog_inputs else " (not an input on this model: reads 0)"
        yield Register(
            0x003 + k, f"analog_input[{k}]", R, f"analog input No {k}{note}", Kind.ANALOG_INPUT, k
        )
    for k in range(8):
        yield Register(
            0x00B + k,
            f"channel_state[{k}]",
            R,
            f"State of channel No {k} (bit 1 fallback, 4 < low, 5 > high)",
            Kind.CHANNEL_STATE,
            k,
        )
    yield Register(
        0x013,
        "command[0]",
        RW,
        "Digital outputs command: bits 11-08 blinking, 03-00 states",
        Kind.COMMAND,
        0,
    )
    for k in range(8):
        fitted = k in model.analog_outputs
        note = "" if fitted else " (not an output on this model: reads 0)"
        yield Register(
            0x014 + k,
            f"analog_output[{k}]",
            RW if fitted else R,
            f"Analog output No {k}{note}",
            Kind.ANALOG_OUTPUT,
            k,
        )
    yield Register(
        0x01C,
        "direct_io",
        R,
        "Bits 0 to 3: direct inputs (not filtered) Bits 8 to B: direct outputs",
        Kind.DIRECT_IO,
    )
    yield Register(
        0x01D, "filter_0", MP, "filtered time of levels 0 digital inputs (Tb=5ms)", Kind.FILTER, 0
    )
    yield Register(
        0x01E, "filter_1", MP, "filtered time of levels 1 digital inputs (Tb=5ms)", Kind.FILTER, 1
    )
    yield from _blink_words(0x01F)


def _analog_parameter_words(model: TesModel) -> Iterator[Register]:
    # §6.4.8 - 6.4.11
    for k in range(8):
        yield Register(
            0x023 + k,
            f"low_threshold[{k}]",
            MP,
            f"low threshold of analog input No {k}",
            Kind.LOW_THRESHOLD,
            k,
        )
    for k in range(8):
        yield Register(
            0x02B + k,
            f"high_threshold[{k}]",
            MP,
            f"high threshold of analog input No {k}",
            Kind.HIGH_THRESHOLD,
            k,
        )
    for k in range(8):
        yield Register(
            0x033 + k,
            f"threshold_outputs[{k}]",
            MP,
            f"Outputs associated to analog input No {k} (high byte: high threshold)",
            Kind.THRESHOLD_OUTPUTS,
            k,
        )
    yield Register(
        0x03B,
        "threshold_polarity",
        MP,
        "digital outputs polarity commanded by thresholds (bit i = output i)",
        Kind.THRESHOLD_POLARITY,
    )
    yield Register(
        0x03C,
        "watchdog",
        MP,
        "maximum time (1/10 s) separating two master requests on RS485",
        Kind.WATCHDOG,
    )
    yield Register(
        0x03D,
        "fallback_command",
        MP,
        "Fallback position; command word for 4 digital outputs",
        Kind.FALLBACK_COMMAND,
    )
    for k in range(8):
        yield Register(
            0x03E + k,
            f"fallback_value[{k}]",
            MP,
            f"analog output fallback value No {k}",
            Kind.FALLBACK_VALUE,
            k,
        )
    yield Register(
        0x046,
        "fallback_enable",
        MP,
        "Fallback authorisation for analog outputs: one bit per output",
        Kind.FALLBACK_ENABLE,
    )


@functools.cache
def memory_map(model: TesModel) -> tuple[Register, ...]:
    """The documented words of ``model``'s map, by address (built once per model)."""
    if model.family is Family.DIGITAL_INPUTS:
        regs = tuple(_digital_inputs_map(model))
    elif model.family is Family.DIGITAL_OUTPUTS:
        regs = tuple(_digital_outputs_map())
    else:
        regs = tuple(_analog_map(model))
    return tuple(sorted(regs, key=lambda r: r.address))


def coherent_from(model: TesModel) -> int:
    """First address of the 32-bit area that may answer "slave not ready" (AMB-TES-28)."""
    if model.family is Family.DIGITAL_INPUTS:
        return 0x025
    if model.family is Family.ANALOG:
        return 0x056
    return 0x10000  # TES 32 ST: no 32-bit area


@functools.cache
def register_table(model: TesModel) -> Mapping[int, Register]:
    """address -> Register of ``model``'s map, read only, shared by every TES of the model."""
    return MappingProxyType({r.address: r for r in memory_map(model)})


@functools.cache
def register_names(model: TesModel) -> Mapping[str, Register]:
    """name -> Register of ``model``'s map (``"analog_input[3]"``, ``"rs485.crc_errors"``)."""
    return MappingProxyType({r.name: r for r in memory_map(model)})
