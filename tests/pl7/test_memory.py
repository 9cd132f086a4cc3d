"""The compiled program gives the same results through the readers and writers of
a ProgramMemory that lends no cells as through the cells of InMemory."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.pl7 import FAULT_BIT, Executor, InMemory, ProgramFault, parse
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.memory import Cell

from . import test_aem_tank
from .helpers import EXAMPLES


class NoCells(InMemory):
    """Every object through its reader and writer (what a PLC may choose)."""

    def cell(self, obj: object) -> Cell | None:
        return None


PROGRAM = (
    "! SET B3;7->W23->W24;I5,0[4]->O16,0[4]->O16,C[4];SHR 8(IW5,1)->O17,4[8]\n"
    "! IF [W23>W24+1]+NOT B3 THEN 1->W1 ELSE 2->W1;INC W2;W0(W1)->W130(W2);SET W5,F\n"
    "! 0->B1[8];W23[2]->W40[2];BTA(W23)->W50[3];RE(B3)->B20;FE(B3)->B21;W5,F->OW4,1,1\n"
    "! WHILE [W9<4] DO INC W9;W9*3->W10\n"
)


@pytest.mark.parametrize("cycles", [1, 3])
def test_readers_and_writers_match_cells(cycles: int) -> None:
    results = []
    for memory in (InMemory(), NoCells()):
        executor = Executor(parse(PROGRAM), memory)
        memory.module(0, 5).i[:4] = [1, 0, 1, 1]
        memory.module(0, 5).iw[1] = 0xA500
        for _ in range(cycles):
            executor.run_master_task()
        results.append((memory.b, memory.w, memory.module(1, 6).o, memory.module(1, 7).o))
        results.append(memory.module(0, 4).ow)
    assert results[0:2] == results[2:4]


def test_the_tank_program_without_cells(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(test_aem_tank, "InMemory", NoCells)
    test_aem_tank.test_the_tank_program_configures_the_module_and_writes_both_thresholds()
    test_aem_tank.test_the_tank_program_copies_the_measurements_into_w0_w7()
    test_aem_tank.test_the_fault_processing_reacts_to_a_broken_input()


def test_a_memory_fault_in_a_writer_is_a_program_fault() -> None:
    class Refusing(NoCells):
        def word_writer(self, obj: t.Internal | t.ModuleObj | t.TxtField):  # type: ignore[override]
            def write(value: int) -> None:
                raise ProgramFault(f"{obj} refused {value}")

            return write

    memory = Refusing()
    executor = Executor(parse("! 5->W1\n! SET B1"), memory)
    executor.run_master_task()
    assert memory.sy[FAULT_BIT] == 1 and memory.b[1] == 1
    assert "refused 5" in executor.faults[0].message


def test_examples_exist() -> None:
    names = sorted(p.name for p in Path(EXAMPLES).glob("*.pl7"))
    assert names == ["aem811_tank.pl7", "dem24_assembly.pl7", "scm_exchange.pl7"]
