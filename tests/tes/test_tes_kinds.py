"""Register kinds are an enum; every kind has a reader, every writable word a writer."""

from __future__ import annotations

import pytest

from fieldtwin.errors import ProtocolError
from fieldtwin.tes import MODELS, Tes
from fieldtwin.tes.access import _READERS, _WRITERS
from fieldtwin.tes.kinds import Kind
from fieldtwin.tes.memmap import Access, Register, memory_map, register_table
from fieldtwin.tes.params import param_specs


def test_the_37_kinds_all_have_a_reader() -> None:
    assert len(Kind) == 37 and set(_READERS) == set(Kind)
    used = {reg.kind for model in MODELS.values() for reg in memory_map(model)}
    assert used == set(Kind)


@pytest.mark.parametrize("model", list(MODELS))
def test_every_writable_word_has_a_writer(model: str) -> None:
    for reg in memory_map(MODELS[model]):
        assert isinstance(reg.kind, Kind)
        if reg.access.writable:
            assert reg.kind in _WRITERS, reg


def test_an_unknown_kind_is_an_error_never_a_fall_through() -> None:
    with pytest.raises(ValueError, match="'colour' is not a valid Kind"):
        Kind("colour")
    tes = Tes("TES 32EST")
    odd = Register(0x008, "reserved_008", Access.RW, "a reserved word made writable", Kind.ZERO)
    with pytest.raises(ProtocolError, match=r"word 008h \(reserved_008\) is read only"):
        tes.registers.put(odd, 1, tes.clock.now)


def test_tables_are_built_once_per_model_and_shared() -> None:
    a, b = Tes("TES 8EA"), Tes("TES 8EA")
    assert a.registers.table is b.registers.table is register_table(MODELS["TES 8EA"])
    assert memory_map(MODELS["TES 8EA"]) is memory_map(MODELS["TES 8EA"])
    assert param_specs(MODELS["TES 8EA"]) is param_specs(MODELS["TES 8EA"])
    with pytest.raises(TypeError):
        a.registers.table[0x000] = a.registers.table[0x001]  # type: ignore[index]
