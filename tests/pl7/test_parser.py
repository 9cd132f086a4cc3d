"""Every construct of issue 13 item 1 parses to the tree it means (AEM 5.1, DEM 5.3-4,
SCM 4.6 listings)."""

from __future__ import annotations

import pytest

from fieldtwin.pl7 import parse
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.printer import format_program
from fieldtwin.tsx.addressing import parse_object

from .helpers import dump


def body(text: str) -> tuple[t.Statement, ...]:
    section = parse(text).sections[0]
    assert isinstance(section, t.Literal)
    sentences = [s for s in section.sentences if isinstance(s, t.Sentence)]
    assert len(sentences) == 1
    return sentences[0].body


def one(text: str) -> str:
    return ";".join(dump(s) for s in body(text))


def mod(name: str) -> t.ModuleObj:
    return t.ModuleObj(parse_object(name))


def test_a_literal_only_program_is_the_pre() -> None:
    program = parse("!     0->W1\n")
    assert [type(s).__name__ for s in program.sections] == ["Literal"]
    assert program.section("PRE") is not None


def test_comments_labels_and_eop_aem_5_1() -> None:
    program = parse("<COLD RESTART\n!L1 :RET\n!EOP\n<after\n")
    section = program.sections[0]
    assert isinstance(section, t.Literal)
    assert section.sentences == (
        t.Comment("COLD RESTART"),
        t.Sentence(1, (t.Ret(),)),
        t.Comment("after"),
    )


def test_sections_pre_chart_post_and_subroutines() -> None:
    text = "%PRE\n!  CALL SR3\n%SR3\n!  RET\n%POST\n!  0->W2\n"
    assert [getattr(s, "name", "CHART") for s in parse(text).sections] == ["PRE", "SR3", "POST"]


def test_if_then_else_over_continuation_lines_aem_5_1_l1() -> None:
    text = (
        "!L1 :IF IW5,0,3 THEN JUMP L2\n"
        "    ELSE 0->B1[8];0->OW5,0->OW5,1; RESET TXT0;JUMP L6\n!L2 :RET\n!L6 :RET"
    )
    section = parse(text).sections[0]
    assert isinstance(section, t.Literal)
    first = section.sentences[0]
    assert isinstance(first, t.Sentence) and first.label == 1
    (statement,) = first.body
    assert isinstance(statement, t.If)
    assert statement.then == (t.Jump(2),)
    assert statement.otherwise == (
        t.Assign(t.Const(0), (t.Table(t.Internal("B", 1), 8),)),
        t.Assign(t.Const(0), (mod("OW5,0"), mod("OW5,1"))),
        t.TxtOp("RESET", 0),
        t.Jump(6),
    )


def test_while_do_dem_5_3_4() -> None:
    assert one("! WHILE [W121<W120]\n  DO CALL SR0;INC W121\n%SR0\n!RET") == (
        "While(Compare('<',W121,W120),[Call(0),Step(True,W121)])"
    )


def test_jump_call_ret_set_reset() -> None:
    assert one("!L1 :SET B3;RESET OW5,0,C;CALL SR1;JUMP L1;RET\n%SR1\n!RET") == (
        "SetBit(B3,True);SetBit(ModuleObj(OW5,0,C),False);Call(1);Jump(1);Ret()"
    )


def test_text_block_instructions_and_fields_aem_scm() -> None:
    assert one("! EXCHG TXT0;INPUT TXT1;OUTPUT TXT2;RESET TXT3") == (
        "TxtOp('EXCHG',0);TxtOp('INPUT',1);TxtOp('OUTPUT',2);TxtOp('RESET',3)"
    )
    assert one("! IF TXT0,D.[TXT0,V=H'FE'].NOT TXT0,E THEN H'563'->TXT0,M;68->TXT0,L") == (
        "If(Binary(AND,Binary(AND,TxtField(0,'D'),Compare('=',TxtField(0,'V'),Const(254,HEX))),"
        "Not(TxtField(0,'E'))),[Assign(Const(1379,HEX),[TxtField(0,'M')]),"
        "Assign(Const(68,DEC),[TxtField(0,'L')])],None)"
    )


def test_symbol_txt_1_is_txt1_dem_5_3_4() -> None:
    assert body("! IF NOT Txt_1,D THEN EXCHG Txt_1") == body("! IF NOT TXT1,D THEN EXCHG TXT1")


@pytest.mark.parametrize("field", ["M", "C", "L", "V", "R", "S", "D", "E"])
def test_every_text_block_field(field: str) -> None:
    target = "B1" if field in "DE" else "W1"
    assert body(f"! TXT4,{field}->{target}")[0] == t.Assign(
        t.TxtField(4, field), (t.Internal(target[0], 1),)
    )


def test_assignment_chains_aem_5_1() -> None:
    assert one("! 0->W23->W24->W25") == "Assign(Const(0,DEC),[W23,W24,W25])"
    assert one("! 0->OW5,0->OW5,1") == "Assign(Const(0,DEC),[ModuleObj(OW5,0),ModuleObj(OW5,1)])"


def test_bit_strings_and_word_tables() -> None:
    assert one("! 0->B1[8]") == "Assign(Const(0,DEC),[Table(B1,8)])"
    assert one("! I5,0[4]->O16,0[4]->O16,C[4]") == (
        "Assign(Table(ModuleObj(I5,0),4),[Table(ModuleObj(O16,0),4),Table(ModuleObj(O16,C),4)])"
    )
    assert one("! 0->W2510[2]") == "Assign(Const(0,DEC),[Table(W2510,2)])"
    assert one("! W139[4]->W181[4]") == "Assign(Table(W139,4),[Table(W181,4)])"
    assert one("! SHR 8(IW5,1)->O17,4[8]") == (
        "Assign(Shift(False,8,ModuleObj(IW5,1)),[Table(ModuleObj(O17,4),8)])"
    )


def test_indexed_words_and_word_bits_dem_sr0() -> None:
    assert one("! W0(W124)->W130(W123)") == "Assign(Indexed(W0,W124),[Indexed(W130,W123)])"
    assert one("! IF W131,A THEN RET") == "If(InternalBit(W131,10),[Ret()],None)"


@pytest.mark.parametrize("op", ["=", "<>", "<", ">", "<=", ">="])
def test_comparisons_in_brackets(op: str) -> None:
    assert (
        one(f"! [IW5,1{op}0]->B4") == f"Assign(Compare('{op}',ModuleObj(IW5,1),Const(0,DEC)),[B4])"
    )


def test_and_or_not_and_parentheses_aem_5_1() -> None:
    assert one("! IF (I5,S+IW5,0,4+B4).B3 THEN RET") == (
        "If(Binary(AND,Binary(OR,Binary(OR,ModuleObj(I5,S),ModuleObj(IW5,0,4)),B4),B3),[Ret()],None)"
    )
    # NOT binds tighter than '.', which binds tighter than '+'
    assert one("! NOT I4,0+I4,3.B1->O3,1") == (
        "Assign(Binary(OR,Not(ModuleObj(I4,0)),Binary(AND,ModuleObj(I4,3),B1)),[ModuleObj(O3,1)])"
    )


def test_edges_dem_post() -> None:
    assert one("! IF NOT (RE(I2,B)+FE(B11)) THEN RET") == (
        "If(Not(Binary(OR,Edge(True,ModuleObj(I2,B)),Edge(False,B11))),[Ret()],None)"
    )


def test_word_operations() -> None:
    assert one("! INC W203;DEC W5") == "Step(True,W203);Step(False,W5)"
    assert one("! SHL 8(SW56 REM 100)OR SW55->W200") == (
        "Assign(Binary(WOR,Shift(True,8,Binary(REM,SW56,Const(100,DEC))),SW55),[W200])"
    )
    assert one("! H'FF' AND W1 XOR W2->W3") == (
        "Assign(Binary(WXOR,Binary(WAND,Const(255,HEX),W1),W2),[W3])"
    )
    assert one("! W1+W2-W3*W4/W5->W6") == (
        "Assign(Binary(SUB,Binary(ADD,W1,W2),Binary(DIV,Binary(MUL,W3,W4),W5)),[W6])"
    )


def test_constants_hex_b_decimal_and_text() -> None:
    assert one("! H'00A0'->W1;B'100'->W2;160->W3;M'on'->W4") == (
        "Assign(Const(160,HEX),[W1]);Assign(Const(256,B),[W2]);"
        "Assign(Const(160,DEC),[W3]);Assign(Const(28271,TEXT),[W4])"
    )


def test_bta_dem_sr0() -> None:
    assert one("! BTA(W150)->W160[3]") == "Assign(Bta(W150),[Table(W160,3)])"


def test_objects_of_issue_13() -> None:
    text = (
        "! B1.SY0.X0.XM0.I14,0.I5,S.IW5,2,D.OW4,1,0.O3,4.W1,0.SW3,F->O3,0;CW3+SW50+IW23,0+OW5,1->W9"
    )
    program = "%CHART\nCHART INITIAL 0\nCHART T: 0>M0\n!  B1\nXM0 T: IN>OUT\n!  B1\n%POST\n" + text
    post = parse(program).section("POST")
    assert isinstance(post, t.Literal)
    sentence = post.sentences[0]
    assert isinstance(sentence, t.Sentence)
    assert dump(sentence.body) == (
        "[Assign(Binary(AND,Binary(AND,Binary(AND,Binary(AND,Binary(AND,Binary(AND,Binary(AND,"
        "Binary(AND,Binary(AND,Binary(AND,B1,SY0),X0),XM0),ModuleObj(I14,0)),ModuleObj(I5,S)),"
        "ModuleObj(IW5,2,D)),ModuleObj(OW4,1,0)),ModuleObj(O3,4)),InternalBit(W1,0)),"
        "InternalBit(SW3,15)),[ModuleObj(O3,0)]),Assign(Binary(ADD,Binary(ADD,Binary(ADD,CW3,SW50),"
        "ModuleObj(IW23,0)),ModuleObj(OW5,1)),[W9])]"
    )


def test_chart_as_the_dem_listing_writes_it() -> None:
    text = (
        "%CHART\nCHART INITIAL M0\nCHART T: M0 > M0\n!   B1\nCHART S(A)0\n<c\n!  SET B2\n"
        "T: 0>1\n!   I2,0\nXM0 S(A) IN\n!   RESET OW4,0,C\nXM0 T: IN>0\n!   NOT IW4,0,C\n"
        "XM0 S(D) 0\n!   RESET B3\nXM0 T: 0>OUT\n!   [IW4,5=0]\nCHART T: M0>0\n! B2\nT: 1>0\n! B2\n"
    )
    chart = parse(text).section("CHART")
    assert isinstance(chart, t.Chart)
    assert [dump(i) for i in chart.items] == [
        "Initial(['M0'])",
        "Transition(-1,'M0','M0',B1)",
        "StepActions(-1,'0','A',[Comment('c'),Sentence(None,[SetBit(B2,True)])])",
        "Transition(-1,'0','1',ModuleObj(I2,0))",
        "StepActions(0,'IN','A',[Sentence(None,[SetBit(ModuleObj(OW4,0,C),False)])])",
        "Transition(0,'IN','0',Not(ModuleObj(IW4,0,C)))",
        "StepActions(0,'0','D',[Sentence(None,[SetBit(B3,False)])])",
        "Transition(0,'0','OUT',Compare('=',ModuleObj(IW4,5),Const(0,DEC)))",
        "Transition(-1,'M0','0',B2)",
        "Transition(-1,'1','0',B2)",
    ]


def test_empty_and_label_only_sentences_dem_post() -> None:
    section = parse("!L10 :\n!\n").sections[0]
    assert isinstance(section, t.Literal)
    assert section.sentences == (t.Sentence(10, ()), t.Sentence(None, ()))


def test_the_arrow_of_the_manuals_is_accepted() -> None:
    assert body("! S47→B7".replace("S47", "SY7")) == body("! SY7->B7")


def test_printing_puts_parentheses_only_where_needed() -> None:
    text = "! (B1+B2).NOT (B3.B4)+B5->B6;W1-(W2-W3)->W4;(W1+W2)*W3->W5\n"
    printed = format_program(parse(text))
    assert "(B1+B2).NOT (B3.B4)+B5->B6;W1-(W2-W3)->W4;(W1+W2)*W3->W5" in printed
    assert parse(printed) == parse(text)
