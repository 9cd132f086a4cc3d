"""Properties: any text is a program or a Pl7Error (never another exception); any
well-formed program that passes the checker runs without raising."""

from __future__ import annotations

import contextlib

from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fieldtwin.pl7 import Executor, InMemory, Pl7Error, check, format_program, parse
from fieldtwin.pl7 import tree as t

from .test_roundtrip import programs

PIECES = st.sampled_from(
    [
        "!",
        "!L1 :",
        "!EOP",
        "<c",
        "%PRE",
        "%SR1",
        "%CHART",
        "%POST",
        "IF",
        "THEN",
        "ELSE",
        "WHILE",
        "DO",
        "JUMP L1",
        "CALL SR1",
        "RET",
        "SET",
        "RESET",
        "EXCHG",
        "TXT0",
        "TXT0,D",
        "->",
        ";",
        ".",
        "+",
        "-",
        "*",
        "/",
        "REM",
        "AND",
        "NOT",
        "(",
        ")",
        "[",
        "]",
        "=",
        "<>",
        "<",
        "B1",
        "W2",
        "CW3",
        "SY0",
        "X0",
        "XM0",
        "IW5,2,D",
        "OW4,1",
        "I5,S",
        "O16,C[4]",
        "W0(W1)",
        "B1[8]",
        "H'FF'",
        "B'100'",
        "M'on'",
        "7",
        "RE(B1)",
        "SHL 8(W1)",
        "BTA(W1)",
        "CHART S(A)0",
        "CHART T: 0>1",
        "XM0 T: IN>OUT",
        "CHART INITIAL 0",
        "\n",
        "\n  ",
        ",",
    ]
)


@settings(max_examples=400)
@given(st.lists(PIECES, max_size=25).map(" ".join))
def test_any_text_is_a_program_or_a_pl7_error(text: str) -> None:
    try:
        program = parse(text)
    except Pl7Error as err:
        assert err.line >= 1 and err.column >= 1
        return
    try:
        check(program)
    except Pl7Error:
        return
    Executor(program, InMemory()).run_master_task()


@settings(max_examples=300)
@given(st.text(max_size=60))
def test_any_characters_are_a_program_or_a_pl7_error(text: str) -> None:
    with contextlib.suppress(Pl7Error):
        parse(text)


def _checks(program: t.Program) -> bool:
    try:
        check(program)
    except Pl7Error:
        return False
    return True


@settings(max_examples=200)
@given(programs())
def test_a_checked_program_runs_without_raising(program: t.Program) -> None:
    assume(_checks(program))
    memory = InMemory()
    executor = Executor(program, memory)
    for cycle in range(3):
        memory.w[1] = cycle * 7  # something for the indexes and conditions to chew on
        executor.run_master_task(cycle * 1_000_000)
        if cycle == 1:
            executor.hot_restart()
    assert parse(format_program(program)) == program
