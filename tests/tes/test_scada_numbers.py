"""docs/scada.md's 1-based coil and register numbers agree with the twin's memory map
(bit address = word x 16 + bit, TES 7.1.2; reference = address + 1)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fieldtwin.tes.memmap import memory_map
from fieldtwin.tes.tesis import MODELS

PAGE = Path(__file__).resolve().parents[2] / "docs" / "scada.md"
# (models, row label start, the map's register name, bit offset of N in that word)
ROWS = [
    (("TES 16EST", "TES 32EST", "TES 32ET"), "filtered input N", "filtered[0]", 0),
    (("TES 16EST", "TES 32EST", "TES 32ET"), "direct (unfiltered)", "direct[0]", 0),
    (("TES 16EST", "TES 32EST", "TES 32ET"), "memorized input N", "memorized[0]", 0),
    (("TES 16EST", "TES 32EST"), "output N: command", "command[1]", 0),
    (("TES 16EST", "TES 32EST"), "output N: instantaneous", "outputs[0]", 0),
    (("TES 32ST",), "output N: command", "command[0]", 0),
    (("TES 32ST",), "output N: instantaneous", "outputs[0]", 0),
    (("TES 4EA", "TES 8EA", "TES 8SA-U"), "filtered digital", "filtered[0]", 0),
    (("TES 4EA", "TES 8EA", "TES 8SA-U"), "memorized digital", "memorized[0]", 0),
    (("TES 4EA", "TES 8EA", "TES 8SA-U"), "direct digital input", "direct_io", 0),
    (("TES 4EA", "TES 8EA", "TES 8SA-U"), "digital output N: command", "command[0]", 0),
    (("TES 4EA", "TES 8EA", "TES 8SA-U"), "digital output N: direct", "direct_io", 8),
]


def _tables() -> dict[str, str]:
    """Each model group's table, keyed by its bold heading."""
    text = PAGE.read_text("utf-8")
    start = text.index("## Coil, discrete-input and register numbers per model")
    section = text[start : text.index("### Signed and 32-bit values", start)]
    parts = re.split(r"^\*\*(.+?)\*\*", section, flags=re.M)
    return {parts[i]: parts[i + 1] for i in range(1, len(parts), 2)}


def _row(table: str, label: str) -> list[str]:
    for line in table.splitlines():
        if line.startswith(f"| {label}"):
            return [cell.strip() for cell in line.strip("|").split("|")]
    raise AssertionError(f"no row {label!r} in {table}")


@pytest.mark.parametrize(("models", "label", "register", "offset"), ROWS)
def test_bit_references_follow_the_memory_map(
    models: tuple[str, ...], label: str, register: str, offset: int
) -> None:
    tables = _tables()
    for name in models:
        heading = next(h for h in tables if name.removeprefix("TES ") in h)
        cells = _row(tables[heading], label)
        address = {r.name: r.address for r in memory_map(MODELS[name])}[register]
        assert cells[2] == f"{address * 16 + offset + 1} + N", (name, label, cells)
        assert str(address + 1) in cells[3], (name, label, cells)


def test_analog_registers_follow_the_memory_map() -> None:
    regs = {r.name: r.address for r in memory_map(MODELS["TES 8EA"])}
    table = _tables()[next(h for h in _tables() if "8EA" in h)]
    assert _row(table, "analog input N")[3] == f"{regs['analog_input[0]'] + 1} + N"
    assert _row(table, "analog output N")[3] == f"{regs['analog_output[0]'] + 1} + N"
    counter = _row(table, "rising-edge counter")[3]
    high = regs["counter_rise[0].high"]
    assert counter.startswith(f"{high + 1} + 2N (high), {high + 2} + 2N (low)"), counter
    assert regs["counter_rise[0].low"] == high + 1
