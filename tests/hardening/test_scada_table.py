"""docs/scada.md: how to switch output N on each TES model, checked against the twin."""

from __future__ import annotations

import pytest

from fieldtwin.tes import Tes

# model -> (output numbers, command word and bit, state word and bit) per docs/scada.md
MIXED = {"TES 16EST": 8, "TES 32EST": 16}
ANALOG = ("TES 4EA", "TES 4SA", "TES 8EA", "TES 8ESA", "TES 8SA-U")


def _on(tes: Tes, command: int, bit: int) -> None:
    tes.write(command, 1 << bit)
    tes.advance(0.05)


@pytest.mark.parametrize("model", sorted(MIXED))
def test_mixed_models_switch_output_n_by_bit_n_of_00Dh(model: str) -> None:
    for n in range(MIXED[model]):
        tes = Tes(model, slave=1)
        _on(tes, 0x00D, n)
        assert tes.read(0x007) == 1 << n


def test_32st_outputs_by_005h_and_006h() -> None:
    for n in range(32):
        tes = Tes("TES 32ST", slave=1)
        _on(tes, 0x005 if n < 16 else 0x006, n % 16)
        assert (tes.read(0x001) | tes.read(0x002) << 16) == 1 << n


@pytest.mark.parametrize("model", ANALOG)
def test_analog_models_switch_digital_output_n_by_bit_n_of_013h(model: str) -> None:
    for n in range(4):
        tes = Tes(model, slave=1)
        _on(tes, 0x013, n)
        assert (tes.read(0x01C) >> 8) & 0xF == 1 << n
