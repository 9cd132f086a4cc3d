"""Shared set-up for the DEM 24 tests: a PLC with a DEM in slot 4, Text Block helpers."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldtwin.clock import S
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.plc import ExchangeResult, Plc

SLOT = 4
M_CH0 = 0x0400  # TXTi,M = H'xy00'
M_SYS = 0x0463  # TXTi,M = H'xy63'
SELF_TEST_S = 10.0

# DEM 4.1-3 example: "15 July 1994 at 18h 5min 33 sec", indicator 1
JULY_15_1994 = [0x5E07, 0x0F12, 0x0521, 0x0001]
# DEM 5.3-3 assembly-line configuration CW0..CW8
ASSEMBLY = [0x0014, 10, 5, 3, 5, 2, 60, 500, 60]


def make(
    type_name: str = "TSX DEM 2412", model: str = "TSX 87", scan_ms: int = 10, **kw: Any
) -> tuple[Plc, Dem24]:
    plc = Plc(model=model, scan_ms=scan_ms)
    mod = plc.insert(type_name, rack=0, slot=SLOT, **kw)
    plc.advance(SELF_TEST_S + 0.05)
    return plc, mod


def at(plc: Plc, t_s: float) -> None:
    """Run the simulation until simulated time ``t_s`` seconds."""
    plc.advance(max(0.0, t_s - plc.now / S))


def configure(plc: Plc, words: list[int]) -> ExchangeResult:
    """DEM 3.4-2: stop, send H'40' with 18 bytes, back to run."""
    scan = plc.scan_us / S
    plc.write(f"OW{SLOT},0,C", 0)
    plc.advance(3 * scan)
    result = plc.exchange(m=M_SYS, c=0x40, send=words)
    plc.write(f"OW{SLOT},0,C", 1)
    plc.advance(3 * scan)
    return result


def send_time(plc: Plc, table: list[int]) -> ExchangeResult:
    return plc.exchange(m=M_CH0, c=0x02, send=table)


@dataclass(frozen=True)
class Read:
    v: int
    s: int
    exchange: int
    count: int
    messages: list[list[int]]


def read(plc: Plc, exchange: int = 1, count: int = 9) -> Read:
    """DEM 4.2-3: request 1 with (exchange number, count), 234-byte reception table."""
    r = plc.exchange(m=M_CH0, c=0x01, send=[exchange, count], recv_bytes=234)
    words = r.words
    msgs = [words[i : i + 13] for i in range(0, len(words) - 12, 13)]
    return Read(r.v, r.s, words[0] & 0xFF, words[0] >> 8, msgs)


def read_all(plc: Plc) -> list[list[int]]:
    out: list[list[int]] = []
    for _ in range(40):
        got = read(plc)
        if not got.messages:
            return out
        out.extend(got.messages)
    raise AssertionError("stack never emptied")


def stamp(msg: list[int]) -> tuple[int, int, int, int, int, int, int]:
    """(yy, month, day, hour, minute, second, ms) of a message."""
    return (
        msg[2] >> 8,
        msg[2] & 0xFF,
        msg[3] >> 8,
        msg[3] & 0xFF,
        msg[4] >> 8,
        msg[4] & 0xFF,
        msg[5],
    )


def synced(
    config: list[int] | None = None, period_s: int = 60, select: int = 0xFFFFFF, **kw: Any
) -> tuple[Plc, Dem24]:
    """A module configured, running, pulses every ``period_s`` since t = 11 s, time set
    to 15 July 1994 18:05:33 (taken at the pulse at t = 11 + period), selection set,
    stack emptied."""
    plc, mod = make(**kw)
    words = config or [0, 0, 0, 0, 0, 0, period_s, 2, 0]
    assert configure(plc, words).v == 0xFE
    mod.attach_pulse_source(period_s * S, 11 * S)
    plc.write(f"OW{SLOT},2", select & 0xFFFF)
    plc.write(f"OW{SLOT},3", select >> 16)
    at(plc, 11.5)  # first pulse at 11 s: the period reference
    assert send_time(plc, JULY_15_1994).v == 0xFE
    at(plc, 11.0 + period_s + 0.001)
    assert mod.timebase.ready
    read_all(plc)
    return plc, mod


def unread_default_plant(tmp_path: Path) -> Path:
    """The default plant as it was before its program read the DEM's message stack: the
    AEM manual's tank program alone (aem811_tank.pl7), so nobody reads the stack and it
    fills (for the tests of the DEM's stack and events on a whole plant)."""
    from importlib import resources

    text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text("utf-8")
    assert 'program = "default.pl7"' in text
    text = text.replace('program = "default.pl7"', 'program = "aem811_tank.pl7"')
    path = tmp_path / "default-unread.toml"
    path.write_text(text.replace("tcp://127.0.0.1:5020", "tcp://127.0.0.1:0"))
    return path
