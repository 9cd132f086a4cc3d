"""Golden parse trees of the three manuals' programs (examples/*.pl7): one line per
sentence, comment or chart item, positions left out (tests/pl7/golden/*.tree)."""

from __future__ import annotations

import pytest

from fieldtwin.pl7 import parse

from .helpers import EXAMPLES, GOLDEN, dump_program

NAMES = ["aem811_tank", "dem24_assembly", "scm_exchange"]


@pytest.mark.parametrize("name", NAMES)
def test_golden_tree(name: str) -> None:
    program = parse((EXAMPLES / f"{name}.pl7").read_text(), name)
    golden = (GOLDEN / f"{name}.tree").read_text()
    assert dump_program(program) == golden


def test_the_golden_trees_hold_the_manuals_lines() -> None:
    aem = (GOLDEN / "aem811_tank.tree").read_text()
    # AEM 5.1 SR0 L3, with "0-\n>W21" and H’40' read as 0->W21 and H'40'
    assert (
        "Sentence(3,[If(Not(ModuleObj(IW5,0,C)),[Assign(Const(1379,HEX),[TxtField(0,'M')]),"
        "Assign(Const(64,HEX),[TxtField(0,'C')]),Assign(Const(1,DEC),[W20]),"
        "Assign(Const(0,DEC),[W21]),Assign(Const(68,DEC),[W22]),"
        "Assign(Const(0,DEC),[W23,W24,W25]),TxtOp('EXCHG',0),SetBit(B1,True)],None)])"
    ) in aem
    dem = (GOLDEN / "dem24_assembly.tree").read_text()
    # DEM 5.3-4 XM0 step 0, with the scan's H(463( and H(40( read as H'463' and H'40'
    assert "StepActions(0,'0','A',[Comment('module configuration loading')," in dem
    assert "Assign(Const(1123,HEX),[TxtField(0,'M')])" in dem
