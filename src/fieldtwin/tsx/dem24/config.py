"""The DEM 24 configuration: 9 words (DEM 3.2-1), its checks (3.4-3) and the default (3.3).

Word 0 is binary (AI EXT bit 0, OSC bit 2, LOG bit 4, DEF bit 6); words 1..8 are
decimal: FILT, T-MAX, N-MAX, T-MIN, N-MIN, T-SYN, DRIFT, PER.  A refused table gives
the diagnostic bits IWxy,2,1..5 of the first error found (3.1-3).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from fieldtwin.words import words_to_bytes

CONFIG_WORDS = 9
CONFIG_BYTES = 18  # DEM 3.4-2: TXTi,L = 18

# Word 0 bits (DEM 3.2-1)
AI_EXT = 0x0001  # external supply monitoring
OSC = 0x0004  # oscillating-input detection
LOG = 0x0010  # periodic logging of the overall state
DEF = 0x0040  # fallback: 1 = maintain the inputs, 0 = force them to 0
WORD0_DEFINED = AI_EXT | OSC | LOG | DEF

# IWxy,2 diagnostic bits (DEM 2.4-3, 3.1-3)
DIAG_FILT = 1
DIAG_OSC = 2
DIAG_TSYN = 3
DIAG_DRIFT = 4
DIAG_PER = 5

# Fault bit string, 96 bits (DEM 4.3, AMB-DEM-14)
FB_TERMINAL = 16
FB_SUPPLY = 17  # not in the list (bit 17 is missing): our reading, manual-notes
FB_SYNC = 32
FB_STACK_FULL = 33
FB_TIME_REFUSED = 34
FB_CONFIG_REFUSED = 35

FILT_VALUES = (0, 10, 20, 50)  # ms
TSYN_VALUES = (1, 30, 60)  # s
DRIFT_VALUES = (2, 10, 50, 100, 500)  # ms
WINDOW_RANGE = range(1, 241)  # T-MAX, T-MIN: 1..240 s
COUNT_RANGE = range(1, 10)  # N-MAX, N-MIN: 1..9
PER_RANGE = range(1, 241)  # minutes


@dataclass(frozen=True, slots=True)
class Dem24Config:
    word0: int = 0
    filt_ms: int = 0
    t_max_s: int = 0
    n_max: int = 0
    t_min_s: int = 0
    n_min: int = 0
    t_syn_s: int = 60
    drift_ms: int = 2
    per_min: int = 0

    @property
    def supply_monitoring(self) -> bool:
        return bool(self.word0 & AI_EXT)

    @property
    def oscillation(self) -> bool:
        return bool(self.word0 & OSC)

    @property
    def periodic(self) -> bool:
        return bool(self.word0 & LOG)

    @property
    def maintain(self) -> bool:
        return bool(self.word0 & DEF)

    def words(self) -> list[int]:
        return [
            self.word0,
            self.filt_ms,
            self.t_max_s,
            self.n_max,
            self.t_min_s,
            self.n_min,
            self.t_syn_s,
            self.drift_ms,
            self.per_min,
        ]

    def to_bytes(self) -> bytes:
        return words_to_bytes(self.words())


# DEM 3.3: CWi = 0, 0, 0, 0, 0, 0, 60, 2, 0
DEFAULT_CONFIG = Dem24Config()


@dataclass(frozen=True, slots=True)
class Refusal:
    """Why a table was refused: the IWxy,2 diagnostic bits it sets (maybe none)."""

    diag_bits: tuple[int, ...]
    reason: str

    @property
    def diag_word(self) -> int:
        word = 0
        for bit in self.diag_bits:
            word |= 1 << bit
        return word


def check_config(words: Sequence[int]) -> Dem24Config | Refusal:
    """DEM 3.4-3 checks in the order of the diagnostic bits; stop at the first error."""
    if len(words) != CONFIG_WORDS:
        return Refusal((), f"length {2 * len(words)} bytes (18 required)")
    w0, filt, t_max, n_max, t_min, n_min, t_syn, drift, per = words
    if w0 & ~WORD0_DEFINED:
        return Refusal((), f"word 0 H'{w0:04X}' has undefined bits")  # syntax: code not defined
    if filt not in FILT_VALUES:
        return Refusal((DIAG_FILT,), f"FILT {filt} (allowed 0, 10, 20, 50 ms)")
    if w0 & OSC and not (
        t_max in WINDOW_RANGE
        and n_max in COUNT_RANGE
        and t_min in WINDOW_RANGE
        and n_min in COUNT_RANGE
    ):  # 3.2-1: "all 4 values must be programmed"
        return Refusal((DIAG_OSC,), "oscillation parameters (1..240 s, 1..9)")
    if t_syn not in TSYN_VALUES:
        return Refusal((DIAG_TSYN,), f"T-SYN {t_syn} (allowed 1, 30, 60 s)")
    if drift not in DRIFT_VALUES:
        return Refusal((DIAG_DRIFT,), f"DRIFT {drift} (allowed 2, 10, 50, 100, 500 ms)")
    if drift == 500 and t_syn == 1:  # 3.2-1 warning; 3.1-3: bits 3 and 4 together
        return Refusal((DIAG_TSYN, DIAG_DRIFT), "DRIFT 500 ms with T-SYN 1 s")
    if (w0 & LOG and per not in PER_RANGE) or not 0 <= per <= 240:  # AMB-DEM-10
        return Refusal((DIAG_PER,), f"PER {per} (allowed 1..240 min with LOG)")
    return Dem24Config(w0, filt, t_max, n_max, t_min, n_min, t_syn, drift, per)
