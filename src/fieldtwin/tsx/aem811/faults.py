"""The AEM 811 fault bit string (AEM 4.4-1, 7.1); the faults by name are in devices/aem811.

Bits 0..15 are reserved (the twin uses bit 0 for a processor failure, a
blocking fault nobody can read anyway); 16 terminal block, 17 converter, 18
input relays (acquisition/conversion faults: the module stops); from bit 32,
four bits a channel: ELL exceeded, continuity, calculation overflow, EHL
exceeded (application faults: the module keeps running).
"""

from __future__ import annotations

from fieldtwin.tsx.aem811.scaling import Measurement
from fieldtwin.tsx.module import FaultCategory

PROCESSOR = 0  # reserved bit used for the blocking fault (manual-notes)
TERMINAL_BLOCK = 16
CONVERTER = 17
RELAY = 18
CHANNEL_BASE = 32
BELOW, CONTINUITY, OVERFLOW, ABOVE = 0, 1, 2, 3  # offsets within a channel's 4 bits


def channel_bits(channel: int) -> tuple[int, int, int, int]:
    """Fault-string bits of a channel: ELL, continuity, overflow, EHL."""
    base = CHANNEL_BASE + 4 * channel
    return base + BELOW, base + CONTINUITY, base + OVERFLOW, base + ABOVE


def conditions(m: Measurement) -> tuple[bool, bool, bool, bool]:
    return m.below, m.continuity, m.overflow, m.above


def category(bit: int) -> FaultCategory:
    if bit < TERMINAL_BLOCK:
        return FaultCategory.BLOCKING
    if bit < CHANNEL_BASE:
        return FaultCategory.MODULE  # AEM 7.1-1; terminal block: AMB-AEM-29
    return FaultCategory.APPLICATION


def describe(data: bytes) -> list[str]:
    """The names of the bits set in a fault bit string (for the status and docs)."""
    names = {PROCESSOR: "processor", TERMINAL_BLOCK: "terminal block", CONVERTER: "converter"}
    names[RELAY] = "input relays"
    kinds = ("ELL exceeded", "continuity", "calculation overflow", "EHL exceeded")
    out = []
    for bit in range(8 * len(data)):
        if data[bit // 8] >> (bit % 8) & 1:
            if bit >= CHANNEL_BASE:
                channel, kind = divmod(bit - CHANNEL_BASE, 4)
                out.append(f"channel {channel} {kinds[kind]}")
            else:
                out.append(names.get(bit, f"bit {bit}"))
    return out
