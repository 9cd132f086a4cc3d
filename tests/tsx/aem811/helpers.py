"""Shared set-up for the AEM 811 tests: a PLC with the module in rack 0 slot 5."""

from __future__ import annotations

from fieldtwin.clock import MS
from fieldtwin.tsx.aem811 import Aem811
from fieldtwin.tsx.plc import ExchangeResult, Plc
from fieldtwin.words import to_unsigned

SYS = 0x0563  # TXTi,M = H'0563': the module system
CHN = 0x0500  # TXTi,M = H'0500': the channels
SELF_TEST_S = 10.0

# AEM 5.1 as its text describes it (AMB-AEM-03): channels 0..3 level, 4/20 mA,
# user 0..10000 mm; channels 4..7 flow, 0/10 V, square root, user 0..20000
# (1/1000 l/min), with the continuity test ("selected so as to monitor the
# operation of the pressure transducer"): H'21C1'.
TANK_CONFIG = [0x00A0, 30]
for _ch in range(4):
    TANK_CONFIG += [0x00C0 | _ch, 0x80C0, 10000, 0]
for _ch in range(4, 8):
    TANK_CONFIG += [0x00C0 | _ch, 0x21C1, 20000, 0]
TANK_THRESHOLD_0 = [1000, 1000, 1000, 1000, 15000, 15000, 15000, 15000]  # CW100..107
TANK_THRESHOLD_1 = [8000, 8000, 8000, 8000, 0, 0, 0, 0]  # CW108..115


def make(
    model: str = "TSX 87", *, code: int | None = None, quantize: bool = True
) -> tuple[Plc, Aem811]:
    plc = Plc(model=model, scan_ms=10)
    slot = 5 if model != "TSX 47-20" else 1
    mod = plc.insert("TSX AEM 811", rack=0, slot=slot, code=code, quantize=quantize)
    assert isinstance(mod, Aem811)
    return plc, mod


def ready(model: str = "TSX 87", **kw: object) -> tuple[Plc, Aem811]:
    """A module past its initial self-test, stopped, default configuration."""
    plc, mod = make(model, **kw)  # type: ignore[arg-type]
    plc.advance(SELF_TEST_S + 0.02)
    return plc, mod


def words(values: list[int]) -> list[int]:
    return [to_unsigned(v) for v in values]


def configure(plc: Plc, table: list[int]) -> ExchangeResult:
    return plc.exchange(m=SYS, c=0x40, send=words(table))


def run(plc: Plc, mod: Aem811) -> int:
    """OWxy,0,C = 1 and run until the module is in Run; returns the Run time (us)."""
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    assert mod.running and mod.run_started_at_us is not None
    return mod.run_started_at_us


def until(plc: Plc, at_us: int) -> None:
    plc.clock.run_until(at_us)


def at(start: int, ms: float) -> int:
    return start + round(ms * MS)
