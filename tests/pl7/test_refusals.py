"""Every refused form is a Pl7Error (a ConfigError) with line, column, token and
what was expected (issue 13: "refused at load with line, column, the token")."""

from __future__ import annotations

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.pl7 import Executor, InMemory, Pl7Error, check, parse

# (source, line, column, token, a word of what is expected)
SYNTAX = [
    ("! 0->W1\n! 0-W2", 2, 7, "", "->"),  # a broken arrow (the scan's "0-\n>W21")
    ("! H(463(->TXT0,M", 1, 3, "H", "an object"),  # the scan's H(463( for H'463'
    ("! 0->0W4,2", 1, 6, "0", "object to write"),  # 0W4 for OW4
    ("! SET 03,4", 1, 7, "03", "bit to set"),  # 03,4 for O3,4
    ("! I2,8->IW4,1,0", 1, 9, "IW4", "object to write"),  # an input is not written
    ("! 5->CW3", 1, 6, "CW3", "object to write"),  # constant words come from the plant file
    ("! B1->W1", 1, 7, "W1", "takes bit"),  # a bit into a word
    ("! W1->B1", 1, 7, "B1", "takes word"),
    ("! W1[2]->W3[3]", 1, 10, "W3", "takes word table [2]"),
    ("! IF W1 THEN RET", 1, 6, "W1", "bit condition"),
    ("! IF B1 RET", 1, 9, "RET", "THEN"),
    ("! IF B1 THEN", 1, 13, "", "instruction"),
    ("! IF B1 THEN IF B2 THEN RET", 1, 14, "IF", "only start a sentence"),
    ("! B1+W2->B3", 1, 6, "W2", "bit operand"),
    ("! W1.W2->W3", 1, 5, ".", "operator for word"),
    ("! NOT W1->B2", 1, 7, "W1", "bit after NOT"),
    ("! [B1=B2]->B3", 1, 4, "B1", "a word"),
    ("! [W1 W2]->B3", 1, 7, "W2", "comparison"),
    ("! [W1=W2->B3", 1, 9, "->", "']'"),
    ("! RE(W1)->B1", 1, 6, "W1", "bit object inside RE"),
    ("! SHL 17(W1)->W2", 1, 7, "17", "shift count"),
    ("! H'12345'->W1", 1, 3, "H'12345'", "hex digits"),
    ("! H'12G'->W1", 1, 3, "H'12G'", "hex digits"),
    ("! H'12->W1", 1, 3, "H'12->W1", "closing '"),
    ("! 70000->W1", 1, 3, "70000", "0..65535"),
    ("! M'abc'->W1", 1, 3, "M'abc'", "two characters"),
    ("! IW5,8->W1", 1, 3, "IW5", "word index"),
    ("! I5,G->B1", 1, 3, "I5", "bit"),
    ("! O5,S->B1", 1, 3, "O5", "fault bit"),
    ("! IW123,0->W1", 1, 3, "IW123", "object"),
    ("! 0->O16,C[5]", 1, 12, "5", "bit string"),
    ("! 0->SY3[2]", 1, 6, "SY3", "table of Bi"),
    ("! 0->W1[0]", 1, 9, "0", "table length"),
    ("! TXT0,Q->W1", 1, 8, "Q", "Text Block field"),
    ("! TXT0->W1", 1, 7, "->", "Text Block field"),
    ("! EXCHG W1", 1, 9, "W1", "Text Block TXTi"),
    ("! JUMP 3", 1, 8, "3", "label Ln"),
    ("! CALL L3", 1, 8, "L3", "subroutine SRi"),
    ("! THEN B1", 1, 3, "THEN", "instruction"),
    ("! W1 W2", 1, 6, "W2", "->"),
    ("! 0->W1 W2", 1, 9, "W2", "end of the sentence"),
    ("! 0->W1 ; ?", 1, 11, "?", "operator"),
    ("!L1 :EOP", 1, 6, "EOP", "without a label"),
    ("!EOP\n! 0->W1", 2, 1, "!", "after !EOP"),
    ("%MAIN\n! RET", 1, 1, "MAIN", "section"),
    ("! W0(B1)->W2", 1, 6, "B1", "index word"),
    ("%CHART\n! B1", 2, 1, "!", "step CHART S(A)n"),
    ("%CHART\nCHART S(P)1\n! B1", 2, 9, "P", "A (actions on activation)"),
    ("%CHART\nCHART T: 1-2\n! B1", 2, 11, "-", "'>'"),
    ("%CHART\nCHART T: 1>2\n  B1", 3, 3, "B1", "condition"),
    ("%CHART\nCHART T: 1>2\n! W1", 3, 3, "W1", "bit condition"),
    ("%CHART\nCHART T: 1>2\n! B1;B2", 3, 5, ";", "end of the condition"),
    ("%CHART\nCHART T: 1>X\n! B1", 2, 12, "X", "step number"),
    ("%CHART\nCHART FOO", 2, 7, "FOO", "S(A)n"),
]


@pytest.mark.parametrize(("text", "line", "column", "token", "expected"), SYNTAX)
def test_refused_at_parse(text: str, line: int, column: int, token: str, expected: str) -> None:
    with pytest.raises(Pl7Error) as info:
        parse(text, "prog.pl7")
    err = info.value
    assert isinstance(err, ConfigError)
    assert (err.line, err.column, err.token) == (line, column, token), str(err)
    assert expected in err.expected, str(err)
    assert str(err).startswith(f"prog.pl7: line {line}, column {column}: ")


CHECK = [
    ("!L1 :RET\n!L1 :RET", 2, 1, "L1", "not used before"),
    ("! JUMP L4\n!L3 :RET", 1, 8, "L4", "label of this section (L3)"),
    ("! CALL SR2\n%SR1\n! RET", 1, 8, "SR2", "subroutine of the program (SR1)"),
    ("%SR1\n! JUMP L1\n%PRE\n!L1 :RET", 2, 8, "L1", "label of this section (none)"),
    ("! 0->W4096", 1, 6, "W4096", "W0..W4095"),
    ("! 0->W4095[2]", 1, 6, "W4095[2]", "W0..W4095"),
    ("! SET B4096", 1, 7, "B4096", "B0..B4095"),
    ("! EXCHG TXT64", 1, 9, "TXT64", "TXT0..TXT63"),
    ("! TXT70,D->B1", 1, 3, "TXT70", "TXT0..TXT63"),
    ("! X3->B1", 1, 3, "X3", "step of the chart"),
    ("%PRE\n! RET\n%PRE\n! RET", 3, 1, "%PRE", "one section"),
    ("%CHART\nCHART T: 0>1\n! B1", 1, 1, "%CHART", "initial step"),
    (
        "%CHART\nCHART INITIAL 0\nCHART T: 0>1\n! B1\nCHART T: 0>1\n! B2",
        5,
        1,
        "T: 0>1",
        "one transition",
    ),
    ("%CHART\nCHART INITIAL 0\nCHART S(A)5\n! SET B1", 3, 1, "S(A)5", "transition or initial"),
    (
        "%CHART\nCHART INITIAL 0\nCHART S(A)0\n! SET B1\nCHART S(A)0\n! SET B2",
        5,
        1,
        "S(A)0",
        "one action block",
    ),
    ("%CHART\nCHART INITIAL M1\nCHART T: M1>0\n! B1", 1, 1, "M1", "expansion XM1"),
    ("%CHART\nCHART INITIAL 0\nXM2 T: IN>OUT\n! B1", 1, 1, "XM2", "macro-step M2"),
    ("%CHART\nCHART INITIAL M0\nXM0 T: IN>1\n! B1", 1, 1, "XM0", "n>OUT"),
    ("%CHART\nCHART INITIAL M0\nXM0 T: OUT>IN\n! B1", 3, 1, "OUT", "OUT ends"),
    ("%CHART\nCHART INITIAL IN\n", 2, 1, "IN", "IN and OUT are in XMj"),
    (
        "%CHART\nCHART INITIAL M0\nCHART S(A)M0\n! SET B1\nXM0 T: IN>OUT\n! B1",
        3,
        1,
        "S(A)M0",
        "XM0",
    ),
    ("%CHART\nCHART INITIAL 0\nCHART T: 0>300\n! B1", 3, 1, "300", "below 256"),
]


@pytest.mark.parametrize(("text", "line", "column", "token", "expected"), CHECK)
def test_refused_at_check(text: str, line: int, column: int, token: str, expected: str) -> None:
    program = parse(text)
    with pytest.raises(Pl7Error) as info:
        check(program, source="prog.pl7")
    err = info.value
    assert (err.line, err.column, err.token) == (line, column, token), str(err)
    assert expected in err.expected, str(err)


def test_the_executor_checks_before_it_runs() -> None:
    with pytest.raises(Pl7Error, match="line 1, column 8: 'L9'"):
        Executor.from_source("! JUMP L9", InMemory(), source="p.pl7")


def test_from_source_names_the_file() -> None:
    with pytest.raises(Pl7Error, match=r"^p.pl7: line 1, column 8"):
        Executor.from_source("! JUMP L9", InMemory(), source="p.pl7")
