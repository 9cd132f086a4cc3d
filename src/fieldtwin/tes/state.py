"""What a TES keeps in RAM besides its I/O: status word, MP words, link counters.

Status-word bits per map (§6.2.1, §6.3.1, §6.4.1; AMB-TES-09).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from fieldtwin.modbus.model import LINE_COUNTERS, Counter, LineTally, Link
from fieldtwin.tes.models import Family
from fieldtwin.tes.params import Value

POWER_ON = 1 << 0  # bit 0: 24 V power on
FALLBACK = 1 << 1  # bit 1: fallback, the master stopped asking
SAFETY = 1 << 2  # bit 2: TES 32ET-S wiring default (short or open circuit)
MEMORIZED = 1 << 3  # bit 3: memorized changes wait to be read (TES-managed)
LOW_ALARM = 1 << 6  # bit 6: an analog input under its low threshold
HIGH_ALARM = 1 << 7  # bit 7: an analog input over its high threshold

# Bits the master resets by writing 0 to them.
MASTER_RESETS = {
    Family.DIGITAL_INPUTS: POWER_ON | FALLBACK | SAFETY,
    Family.DIGITAL_OUTPUTS: POWER_ON | FALLBACK,
    Family.ANALOG: POWER_ON | FALLBACK | LOW_ALARM | HIGH_ALARM,
}

COUNTER_ORDER = (
    Counter.EXCEPTION_REPLIES,
    Counter.NOT_READY_REPLIES,
    Counter.FRAMES_EXECUTED,
    Counter.CRC_ERRORS,
    Counter.WRONG_CHARACTERS,
    Counter.GOOD_FRAMES,
    Counter.NO_SILENCE,
)
_COUNTER_INDEX = {counter: i for i, counter in enumerate(COUNTER_ORDER)}
# the same by the member's id: an Enum's hash is computed in Python (a bump per request)
_COUNTER_SLOT = {id(counter): i for counter, i in _COUNTER_INDEX.items()}


# the parameter of each port's answer delay (§3.1.3), in ms
RS232_DELAY, RS485_DELAY = "rs232.answer_delay_ms", "rs485.answer_delay_ms"


def link_key(link: Link) -> str:
    """The TES counts RS-232 apart; TCP stands in for the RS-485 bus (see docs/tes.md)."""
    return "rs232" if link is Link.RS232 else "rs485"


class LineFault(enum.Enum):
    """Line errors the line glue can be asked to produce on the next frames."""

    BAD_CRC = "bad_crc"
    BROKEN_CHARACTER = "broken_character"


@dataclass(slots=True)
class LinkCounters:
    """§6.2.3.2 diagnosis counters of one link (16-bit, wrapping).

    ``values`` holds what this TES counted itself; a line-wide counter of a line it
    shares a tally with (``LineTally``) adds what the line counted since
    ``base`` (when it joined, powered on or the master wrote the word).  Read
    them with ``value``, write them with ``set``.
    """

    values: list[int] = field(default_factory=lambda: [0] * len(COUNTER_ORDER))
    not_ready_owed: bool = False  # the last answer was "not ready": count it as such
    tally: LineTally | None = None
    base: dict[Counter, int] = field(default_factory=dict)

    def share(self, tally: LineTally) -> None:
        """Count the line-wide counters off ``tally`` from now on (what an earlier
        tally counted is kept)."""
        if self.tally is not None:
            self.values = [self.value(i) for i in range(len(self.values))]
        self.tally, self.base = tally, dict(tally.counts)

    def value(self, i: int) -> int:
        tally = self.tally
        if tally is None:
            return self.values[i]
        counter = COUNTER_ORDER[i]
        if counter not in LINE_COUNTERS:
            return self.values[i]
        return (self.values[i] + tally.counts[counter] - self.base[counter]) & 0xFFFF

    def set(self, i: int, value: int) -> None:
        """A master write of counter word ``i``."""
        self.values[i] = value
        counter = COUNTER_ORDER[i]
        if self.tally is not None and counter in LINE_COUNTERS:
            self.base[counter] = self.tally.counts[counter]

    def bump(self, counter: Counter) -> None:
        if counter is Counter.EXCEPTION_REPLIES and self.not_ready_owed:
            counter = Counter.NOT_READY_REPLIES
        if counter in (Counter.EXCEPTION_REPLIES, Counter.NOT_READY_REPLIES):
            self.not_ready_owed = False
        i = _COUNTER_SLOT[id(counter)]  # members live as long as the process: ids are fixed
        self.values[i] = (self.values[i] + 1) & 0xFFFF


@dataclass(slots=True)
class Ram:
    """The volatile memory of one TES, lost at each power-off (§1).

    ``params`` are the settings in use (the EEPROM's, or the factory's with the
    Prm jumper); ``words`` the MP words and other plain RAM words of the map.
    """

    params: dict[str, Value] = field(default_factory=dict)
    words: dict[int, int] = field(default_factory=dict)
    status: int = 0
    counters: dict[str, LinkCounters] = field(default_factory=dict)
    ao_fallback: int = 0  # bit k: analog output k in its fallback position (§6.4.4 bit 1)
    booted_at: int = 0  # simulated time of the last power-on
    powered: bool = False
    wdg_blinking: bool = False  # §3.1.3 the Wdg LED blinks from the fallback to the next request

    def word(self, address: int) -> int:
        return self.words.get(address, 0)
