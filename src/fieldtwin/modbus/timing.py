"""Character times, RTU silences and the TES transmission-time model (TES 7.2.7).

Nothing here imports the transports: a line's character format is the kernel's
``fieldtwin.charformat.CharFormat`` (the transports' ``LineSettings`` is that value).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from fieldtwin.charformat import CharFormat
from fieldtwin.clock import MS, S
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import (
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    WriteBits,
    WriteWords,
)


def bits_per_char(fmt: CharFormat) -> int:
    """Nb of TES 7.2.7: start + data + parity + stop bits ("from 8 to 11")."""
    return fmt.bits


def char_time(fmt: CharFormat) -> Fraction:
    """One character's duration in microseconds, exactly."""
    return fmt.char_time


@dataclass(frozen=True, slots=True)
class RtuTiming:
    """The silences an RTU receiver keeps, in microseconds.

    ``char_us``: one character; ``t15_us``: the longest silence allowed inside a
    frame; ``t35_us``: the silence that ends a frame.  ``eager``: a frame whose
    length and CRC check is complete at once, without waiting for the silence
    (for streams that carry no timing, such as RTU over TCP).  ``max_lead_us``: on
    a real line, how far behind their arrival characters may still be carried
    at the baud rate; beyond it they are a UART overrun (None: a simulated line,
    whose bytes are all carried, spread after their arrival).
    """

    char_us: int
    t15_us: int
    t35_us: int
    eager: bool = False
    max_lead_us: int | None = None

    def __post_init__(self) -> None:
        if not (self.char_us > 0 and 0 < self.t15_us < self.t35_us):
            raise ConfigError(f"RTU timing {self}: need 0 < char, 0 < t1.5 < t3.5")
        if self.max_lead_us is not None and self.max_lead_us < 0:
            raise ConfigError(f"RTU timing {self}: max_lead_us must be >= 0")

    @classmethod
    def from_format(cls, fmt: CharFormat) -> RtuTiming:
        """Modbus RTU: t1.5 and t3.5 character times of the line's format."""
        ct = char_time(fmt)
        return cls(round(ct), round(ct * 3 / 2), round(ct * 7 / 2))

    def relaxed(
        self, floor_us: int, eager: bool = False, max_lead_us: int | None = None
    ) -> RtuTiming:
        """The same line with silences at least ``floor_us`` / 2 x ``floor_us``.

        Real transports (ptys, TCP) deliver bytes with operating-system jitter and
        no line timing; a floor keeps one frame from being cut in two.
        """
        t15 = max(self.t15_us, floor_us)
        return RtuTiming(self.char_us, t15, max(self.t35_us, 2 * t15), eager, max_lead_us)


# --- TES 7.2.7 transmission time -------------------------------------------------

# TES 7.2.7: "Sq and Sr ... (3 defined in Modbus norm)"; AMB-TES-30 keeps 3.
SILENT_CHARS = 3
# TES 7.2.7: "Typically tr is equal to 1,5 ms"; tq "evaluated to 1.5ms".
TYPICAL_TR_US = 1500
TYPICAL_TQ_US = 1500


@dataclass(frozen=True, slots=True)
class WireTiming:
    """When a reply leaves a real endpoint: the instant a real line delivers its last
    character (TES 7.2.7; issue 15 item 2; docs/modbus.md "Wire timing").

    From the request's last byte as the twin reads it: the request's own Nq
    characters (a pty or a TCP stream hands them over at once), the t3.5 silence
    that ends it, the TES's turnaround ``tr`` (§7.2.7 "typically 1,5 ms"), the
    answer delay (§3.1.3, with any ``late_answer`` fault), then the reply's Nr
    characters.  ``carried``: the transport is a UART at the baud rate, which
    has already taken the request's characters and will take the reply's
    itself, so only the silence, tr and the delay are added.
    """

    char_us: Fraction
    t35_us: int
    turnaround_us: int = TYPICAL_TR_US
    carried: bool = False

    @classmethod
    def from_format(cls, fmt: CharFormat, carried: bool = False) -> WireTiming:
        ct = char_time(fmt)
        return cls(ct, round(ct * 7 / 2), TYPICAL_TR_US, carried)

    def reply_at(self, request_end: int, nq: int, nr: int, delay_us: int) -> int:
        """When a reply of ``nr`` bytes to a request of ``nq`` bytes, read at
        ``request_end``, is sent."""
        gap = self.t35_us + self.turnaround_us + delay_us
        if self.carried:
            return request_end + gap
        return request_end + round(self.char_us * (nq + nr)) + gap


def reply_latency_us(fmt: CharFormat, nq: int, nr: int, delay_us: int = 0) -> int:
    """A master's answer time on a wire-timed pty: from writing the request at once
    to the reply's last character (T of §7.2.7 without Sr and the master's tq)."""
    return WireTiming.from_format(fmt).reply_at(0, nq, nr, delay_us)


def request_bytes(request: Request) -> int:
    """Nq of TES 7.2: bytes of the RTU request frame."""
    match request:
        case WriteWords(values=vs):
            return 9 + 2 * len(vs)  # TES 7.2.2
        case WriteBits(values=vs):
            return 9 + (len(vs) + 7) // 8  # TES 7.2.5, AMB-TES-07
        case ReadExceptionStatus():
            return 4  # TES 7.2.6
    return 8  # TES 7.2.1, 7.2.3, 7.2.4 and fc05


def reply_bytes(request: Request) -> int:
    """Nr of TES 7.2: bytes of the normal RTU reply frame."""
    match request:
        case ReadWords(count=n):
            return 5 + 2 * n  # TES 7.2.1
        case ReadBits(count=n):
            return 5 + (n + 7) // 8  # TES 7.2.4, AMB-TES-07
        case ReadExceptionStatus():
            return 5  # TES 7.2.6
    return 8  # TES 7.2.2, 7.2.3, 7.2.5 and fc05


def exchange_time_us(
    nb: int,
    baud: int,
    nq: int,
    nr: int,
    sq: int = SILENT_CHARS,
    sr: int = SILENT_CHARS,
    tq_us: int = TYPICAL_TQ_US,
    tr_us: int = TYPICAL_TR_US,
) -> int:
    """TES 7.2.7: T = [Nb x 1000 / Vt x (Nq + Sq + Nr + Sr)] + tq + tr, in us."""
    if not 8 <= nb <= 11:
        raise ConfigError(f"Nb {nb}: TES 7.2.7 allows 8 to 11 bits per character")
    if baud <= 0:
        raise ConfigError(f"baud {baud}: must be > 0")
    line = Fraction(nb * S, baud) * (nq + sq + nr + sr)
    return round(line) + tq_us + tr_us


def request_exchange_time_us(
    request: Request,
    fmt: CharFormat,
    tq_us: int = TYPICAL_TQ_US,
    tr_us: int = TYPICAL_TR_US,
) -> int:
    """TES 7.2.7 exchange time of one request and its normal reply on ``fmt``."""
    nq, nr = request_bytes(request), reply_bytes(request)
    return exchange_time_us(bits_per_char(fmt), fmt.baud, nq, nr, tq_us=tq_us, tr_us=tr_us)


def as_ms(us: int) -> float:
    """Microseconds -> milliseconds, for reports."""
    return us / MS
