"""A test double of an intelligent module: only the common part, plus handles to drive it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from fieldtwin.clock import S
from fieldtwin.errors import ConfigError
from fieldtwin.tsx import registry
from fieldtwin.tsx.module import FaultCategory, IntelligentModule, ModuleContext
from fieldtwin.tsx.textblock import Answer, Exchange

DOUBLE = "TEST DOUBLE"
TERMINAL_BLOCK = 16
CONVERTER = 17
SENSOR = 32
CPU = 0


class Double(IntelligentModule):
    type_name = DOUBLE
    hardware_codes = frozenset({900})
    software_codes = frozenset({90})
    self_test_us = 2 * S
    fault_string_bytes = 8
    version_text = "TEST DOUBLE V1.0"
    terminal_block_fault_bit = TERMINAL_BLOCK
    discrete_outputs = 4

    def __init__(self, ctx: ModuleContext, rack: int, slot: int, **kw: Any) -> None:
        super().__init__(ctx, rack, slot, **kw)
        self.held: list[Exchange] = []
        self.power_ups = 0
        self.outputs_seen: list[int] = []

    def on_power_on(self, now: int) -> None:
        self.power_ups += 1
        self.held.clear()

    def fault_category_of(self, bit: int) -> FaultCategory:
        if bit < 16:
            return FaultCategory.BLOCKING
        if bit < 32:
            return FaultCategory.MODULE
        return FaultCategory.APPLICATION

    def handle_request(self, exchange: Exchange, now: int) -> None:
        code = exchange.request.code
        if code == 0x01:  # echo the words back, 1 s later
            self.call_later(S, lambda t: exchange.complete(Answer(0x81, exchange.request.data), t))
        elif code == 0x02:  # held until the test releases it
            self.held.append(exchange)
        elif code == 0x03:  # answers more than asked
            exchange.complete(Answer(0x83, bytes(40)), now)
        else:
            exchange.complete(Answer(0xFD), now)

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        self.i_bits = self.ow[1]
        self.iw[1] = self.ow[1]
        self.outputs_seen.append(self.o_bits)

    def fault_names(self) -> Mapping[str, str]:
        return {"terminal_block": "terminal block removed", "sensor": "sensor wire cut"}

    def inject_fault(self, name: str, active: bool) -> None:
        bits = {"terminal_block": TERMINAL_BLOCK, "sensor": SENSOR}
        if name not in bits:
            raise ConfigError(
                f"unknown fault {name!r} for {self.type_name}"
                f" (allowed: {', '.join(self.fault_names())})"
            )
        self.set_fault(bits[name], active)

    def set_input(self, channel: int, level: bool) -> None:
        """Input ``channel`` (0..15) of the double: the generic face offers it (0 or 1)."""
        self.i_bits = (self.i_bits & ~(1 << channel)) | (int(level) << channel)


registry.register(DOUBLE, Double)


@dataclass(frozen=True)
class Change:
    """A change of a module's face, a clock event ``at_us`` after the step's start (it
    may fall on a refresh): the random histories of the PLC's property tests."""

    at_us: int
    slot: int
    what: str
    index: int
    value: int


@dataclass(frozen=True)
class Command:
    """What the PLC's user (or a test, or the plant) does between two steps of time."""

    what: str
    slot: int
    index: int
    value: int
