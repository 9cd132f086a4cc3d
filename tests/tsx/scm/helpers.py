"""Shared set-up for the SCM tests: a PLC, a module, a configured channel, a memory peer."""

from __future__ import annotations

from typing import Any

from fieldtwin.tsx.plc import ExchangeResult, Plc
from fieldtwin.tsx.scm import MemoryPeer

SLOT = 7
# SCM 3.3 example: 8 bits no parity 2 stops, 9600, rx echo + back-space, ERC-1 = CR not included
CONFIG_3_3 = [0x0802, 0x9600, 0x0000, 0x1001, 0x1000, 0x0D00, 0x0000, 0x0000]
PLAIN_HD = [0x0802, 0x9600, 0, 0, 0, 0, 0, 0]
# SCM 4.6 example CW48..CW56: full-duplex, 8 bits 2 stops, 9600, XON-XOFF (T) + back-space
CONFIG_4_6 = [0x1802, 0x9600, 0, 0x0011, 0, 0, 0, 0, 0]
CHAR_US_9600_8N2 = round(11 * 1_000_000 / 9600)


def make(ref: str = "TSX SCM 2011", slot: int = SLOT, **kw: Any) -> tuple[Plc, Any]:
    plc = Plc(model=kw.pop("model", "TSX 87"), scan_ms=10)
    mod = plc.insert(ref, rack=0, slot=slot, **kw)
    plc.advance(1.05)  # the initial self-test
    return plc, mod


def configure(plc: Plc, slot: int, channel: int, words: list[int]) -> ExchangeResult:
    return plc.exchange(m=(slot << 8) | channel, c=0x40, send=words, txt=30)


def ready(
    ref: str = "TSX SCM 2011", words: list[int] | None = None, channel: int = 0, slot: int = SLOT
) -> tuple[Plc, Any, MemoryPeer]:
    plc, mod = make(ref, slot)
    peer = mod.attach_memory(channel)
    assert configure(plc, slot, channel, words or PLAIN_HD).v == 0xFE
    return plc, mod, peer


def m(channel: int, slot: int = SLOT) -> int:
    return (slot << 8) | channel


def fault_bits(plc: Plc, slot: int = SLOT) -> int:
    r = plc.exchange(m=(slot << 8) | 0x63, c=0x47, recv_bytes=6, txt=31)
    assert r.v == 0x77 and r.s == 6
    return int.from_bytes(r.data, "little")
