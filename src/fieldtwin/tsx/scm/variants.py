"""The TSX SCM module references, their line adaptors and codes (SCM 1.2, 5.2, 7.3).

Each reference of appendix 7.3 fixes the adaptor of each channel and what the
module program allows: half-duplex character strings on both channels, and on
the TSX SCM 2111/2112/2113/2122 full-duplex character strings on channel 1
(SCM 4.4).  The TSX SCM 2116/2146 run channel 1 in half-duplex character mode
on RS-422A/RS-485 (7.3 note (*)).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fieldtwin.errors import ConfigError


class Adaptor(enum.Enum):
    """A line adaptor and its 3-bit code in IWxy,1 (SCM 5.2; bit 6 / E is the MSB)."""

    SCA1 = ("SCA1", 0b001, "RS-232-C 6 signals")
    SCA2 = ("SCA2", 0b010, "20 mA current loop")
    SCA3 = ("SCA3", 0b101, "RS-232-C modem")
    SCA4 = ("SCA4", 0b011, "RS-422-A / RS-485")
    SCA5 = ("SCA5", 0b000, "RS-232-C simplified")
    NONE = ("none", 0b111, "no adaptor")

    def __init__(self, label: str, code: int, description: str) -> None:
        self.label = label
        self.code = code
        self.description = description

    @classmethod
    def parse(cls, text: str, where: str = "adaptor") -> Adaptor:
        for adaptor in cls:
            if adaptor.label.lower() == text.strip().lower():
                return adaptor
        allowed = ", ".join(a.label for a in cls)
        raise ConfigError(f"{where}: {text!r} is not an adaptor (allowed: {allowed})")


class Family(enum.Enum):
    """The module program: 20xy, 21xy, 22xy (SCM preface, 7.3)."""

    SCM20 = "20"
    SCM21 = "21"
    SCM22 = "22"


# SCM 1.2 "Summary of hardware and software configuration codes used"
HARDWARE_CODES = {Family.SCM20: 696, Family.SCM21: 697, Family.SCM22: 698}
CODES_47_20 = frozenset({69, 63})  # hardware code 69, software code 63
# SCM preface: 20xy V1.3 or higher, 21xy V1.0 or higher (7.1 behaviour throughout)
SOFTWARE_VERSION = {Family.SCM20: "V1.3", Family.SCM21: "V1.0", Family.SCM22: "V1.3"}


@dataclass(frozen=True, slots=True)
class Variant:
    """One module reference of appendix 7.3."""

    reference: str  # "TSX SCM 2011"
    family: Family
    adaptors: tuple[Adaptor, Adaptor]  # channel 0, channel 1
    full_duplex_ch1: bool = False

    @property
    def hardware_code(self) -> int:
        return HARDWARE_CODES[self.family]

    @property
    def version_text(self) -> str:
        return f"{self.reference} {SOFTWARE_VERSION[self.family]}"

    @property
    def has_request_7(self) -> bool:
        # SCM 4.3: request 7 is available on the TSX SCM 21xy
        return self.family is Family.SCM21


def _v(ref: str, a0: Adaptor, a1: Adaptor, fd: bool = False) -> Variant:
    family = Family(ref[8:10])
    return Variant(f"TSX SCM {ref[8:]}", family, (a0, a1), fd)


_A = Adaptor
# SCM 7.3 Module versions
VARIANTS: dict[str, Variant] = {
    v.reference: v
    for v in (
        _v("TSX SCM 2011", _A.SCA1, _A.SCA1),
        _v("TSX SCM 2012", _A.SCA1, _A.SCA2),
        _v("TSX SCM 2013", _A.SCA1, _A.SCA3),
        _v("TSX SCM 2014", _A.SCA1, _A.SCA4),
        _v("TSX SCM 2022", _A.SCA2, _A.SCA2),
        _v("TSX SCM 2044", _A.SCA4, _A.SCA4),
        _v("TSX SCM 2055", _A.SCA5, _A.SCA5),
        _v("TSX SCM 2211", _A.SCA1, _A.SCA1),
        _v("TSX SCM 2212", _A.SCA1, _A.SCA2),
        _v("TSX SCM 2213", _A.SCA1, _A.SCA3),
        _v("TSX SCM 2214", _A.SCA1, _A.SCA4),
        _v("TSX SCM 2222", _A.SCA2, _A.SCA2),
        # "RS232C/RS422A/RS485" on channel 0: read as the RS-422A/RS-485 adaptor (manual-notes)
        _v("TSX SCM 2244", _A.SCA4, _A.SCA4),
        # 7.3 (*): Uni-Telway channel 1 runs half-duplex character mode on RS-422A/RS-485
        _v("TSX SCM 2116", _A.SCA1, _A.SCA4),
        _v("TSX SCM 2146", _A.SCA4, _A.SCA4),
        _v("TSX SCM 2111", _A.SCA1, _A.SCA1, True),
        _v("TSX SCM 2112", _A.SCA1, _A.SCA2, True),
        _v("TSX SCM 2113", _A.SCA1, _A.SCA3, True),
        _v("TSX SCM 2122", _A.SCA2, _A.SCA2, True),
    )
}
