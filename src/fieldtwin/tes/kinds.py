"""What answers a word of a TES memory map (§6): one kind per behaviour.

Every :class:`fieldtwin.tes.memmap.Register` carries a ``Kind``; the register
file keeps one reader and one writer per kind, checked complete at import, so
a word of an unknown kind cannot exist and cannot fall through silently.
"""

from __future__ import annotations

import enum


class Kind(enum.StrEnum):
    """The 37 behaviours behind the words of the three maps (§6.2, §6.3, §6.4).

    A ``StrEnum``: ``Kind.COMMAND == "command"``, the name the map shows.
    """

    # status and I/O images (§6.2.1-6.2.2, §6.3.1-6.3.2, §6.4.1-6.4.6)
    STATUS = "status"
    MEMORIZED = "memorized"
    FILTERED = "filtered"
    DIRECT = "direct"
    OUTPUTS = "outputs"
    ZERO = "zero"  # reserved / not used: reads 0
    BLINK_SELECT = "blink_select"
    COMMAND = "command"
    DIRECT_IO = "direct_io"
    ANALOG_INPUT = "analog_input"
    CHANNEL_STATE = "channel_state"
    ANALOG_OUTPUT = "analog_output"
    HISTORY = "history"
    # link diagnosis counters (§6.2.3.2, §6.3.4-5, §6.4.12)
    DIAG_RS485 = "diag_rs485"
    DIAG_RS232 = "diag_rs232"
    # 32-bit values in high / low word pairs (§6.2.4-6.2.5, §6.4.14)
    COUNTER_RISE = "counter_rise"
    COUNTER_FALL = "counter_fall"
    DURATION_1 = "duration_1"
    DURATION_0 = "duration_0"
    CUMULATED_1 = "cumulated_1"
    CUMULATED_0 = "cumulated_0"
    # TES 32ET-S wiring supervision (§6.2.7)
    SC = "sc"
    OC = "oc"
    FAULT = "fault"
    CONNECTION = "connection"
    # MP parameter words (loaded from the EEPROM at power-on)
    FILTER = "filter"
    BLINK = "blink"
    MASK = "mask"
    WATCHDOG = "watchdog"
    STORAGE_PERIOD = "storage_period"
    LOW_THRESHOLD = "low_threshold"
    HIGH_THRESHOLD = "high_threshold"
    THRESHOLD_OUTPUTS = "threshold_outputs"
    THRESHOLD_POLARITY = "threshold_polarity"
    FALLBACK_COMMAND = "fallback_command"
    FALLBACK_VALUE = "fallback_value"
    FALLBACK_ENABLE = "fallback_enable"


# 32-bit values the digital inputs compute (DigitalInputs.value32)
PAIRS = frozenset(
    {
        Kind.COUNTER_RISE,
        Kind.COUNTER_FALL,
        Kind.DURATION_1,
        Kind.DURATION_0,
        Kind.CUMULATED_1,
        Kind.CUMULATED_0,
    }
)

# plain MP words: a write stores the word (and may restart a behaviour)
PARAMETERS = frozenset(
    {
        Kind.FILTER,
        Kind.BLINK,
        Kind.MASK,
        Kind.WATCHDOG,
        Kind.STORAGE_PERIOD,
        Kind.LOW_THRESHOLD,
        Kind.HIGH_THRESHOLD,
        Kind.THRESHOLD_OUTPUTS,
        Kind.THRESHOLD_POLARITY,
        Kind.FALLBACK_COMMAND,
        Kind.FALLBACK_VALUE,
        Kind.FALLBACK_ENABLE,
        Kind.CONNECTION,
    }
)
