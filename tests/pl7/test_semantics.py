"""What each Literal construct does when it runs (issue 13 item 2; docs/pl7.md)."""

from __future__ import annotations

from fieldtwin.pl7 import FAULT_BIT, Executor, InMemory, Started, parse
from fieldtwin.pl7.compiler import MAX_WHILE
from fieldtwin.pl7.executor import MAX_CALL_DEPTH, MAX_JUMPS

from .helpers import load, run


def test_set_reset_and_assignment_chains_aem_5_1() -> None:
    _, m = run("! SET B3;SET B4;RESET B4;7->W23->W24->W25;5->OW5,0->OW5,1")
    assert (m.b[3], m.b[4], m.w[23:26]) == (1, 0, [7, 7, 7])
    assert m.module(0, 5).ow[:2] == [5, 5]


def test_bit_strings_and_tables_aem_5_1_sr2_sr3() -> None:
    executor, memory = load(
        "! I5,0[4]->O16,0[4]->O16,C[4];I5,8[4]->O16,4[4]\n! SHR 8(IW5,1)->O17,4[8];0->B1[8]"
    )
    memory.module(0, 5).i[:12] = [1, 0, 1, 1, 0, 1, 1, 0, 0, 0, 1, 1]
    memory.module(0, 5).iw[1] = 0xA500
    memory.b[1:9] = [1] * 8
    executor.run_master_task()
    m = memory
    o16 = m.module(1, 6).o
    assert o16[0:4] == [1, 0, 1, 1] and o16[12:16] == [1, 0, 1, 1] and o16[4:8] == [0, 0, 1, 1]
    assert m.module(1, 7).o[4:12] == [1, 0, 1, 0, 0, 1, 0, 1]  # H'A5', bit 0 first
    assert m.b[1:9] == [0] * 8


def test_word_tables_fill_and_copy_scm_4_6() -> None:
    executor, memory = load("! 0->W2510[2];W139[4]->W181[4];B1[3]->W5")
    memory.w[2510:2512] = [9, 9]
    memory.w[139:143] = [1, 2, 3, 4]
    executor.run_master_task()
    m = memory
    assert m.w[2510:2512] == [0, 0] and m.w[181:185] == [1, 2, 3, 4]


def test_indexed_words_dem_sr0() -> None:
    executor, memory = load("! W0(W124)->W130(W123)")
    memory.w[0:4] = [10, 11, 12, 13]
    memory.w[124], memory.w[123] = 2, 1
    executor.run_master_task()
    m = memory
    assert m.w[131] == 12


def test_an_index_past_the_table_is_a_program_fault_not_an_exception() -> None:
    executor, memory = load("! W0(W124)->W1;SET B1\n! SET B2")
    memory.w[124] = 5000
    executor.run_master_task()
    m = memory
    assert m.sy[FAULT_BIT] == 1
    assert (m.b[1], m.b[2]) == (0, 1)  # the sentence is abandoned, the next one runs
    (fault,) = executor.faults
    assert (fault.module, fault.line, fault.cycle) == ("PRE", 1, 1)
    assert "W5000" in fault.message


def test_word_bits_and_module_register_bits() -> None:
    executor, memory = load("! IF W131,A THEN SET W5,F;SET OW4,1,1\n! RESET W5,F;SET W5,0")
    memory.w[131] = 1 << 10
    executor.run_master_task()
    m = memory
    assert m.w[5] == 1 and m.module(0, 4).ow[1] == 2


def test_arithmetic_is_on_signed_16_bit_words_and_wraps() -> None:
    executor, memory = load(
        "! W1/2->W2;W1 REM 2->W3;W1*3->W4;32767+1->W5;0-1->W6;H'F0F0' XOR H'FF00'->W7\n"
        "! H'FF' AND W1->W8;H'0F' OR H'F0'->W9;SHL 12(W1)->W10;SHR 12(W1)->W11"
    )
    memory.w[1] = 0xFFF9  # -7
    executor.run_master_task()
    m = memory
    assert m.w[2:7] == [0xFFFD, 0xFFFF, 0xFFEB, 0x8000, 0xFFFF]  # -3, -1, -21
    assert m.w[7:12] == [0x0FF0, 0xF9, 0xFF, 0x9000, 0xF]


def test_comparisons_are_signed() -> None:
    executor, memory = load(
        "! [W1<W2]->B1;[W1>W2]->B2;[W1<=W1]->B3;[W1>=W2]->B4;[W1=H'FFFF']->B5;[W1<>W2]->B6"
    )
    memory.w[1], memory.w[2] = 0xFFFF, 1  # -1 < 1
    executor.run_master_task()
    m = memory
    assert m.b[1:7] == [1, 0, 1, 0, 1, 1]


def test_division_by_zero_is_a_program_fault() -> None:
    executor, m = run("! 5/W1->W2\n! 1->W3")
    assert m.sy[FAULT_BIT] == 1 and m.w[3] == 1 and "division by zero" in executor.faults[0].message


def test_inc_dec_wrap() -> None:
    executor, memory = load("! INC W1;DEC W2")
    memory.w[1], memory.w[2] = 0xFFFF, 0
    executor.run_master_task()
    m = memory
    assert (m.w[1], m.w[2]) == (0, 0xFFFF)


def test_not_and_or_with_parentheses_aem_5_1_l5_l6() -> None:
    executor, memory = load("! (I5,S+IW5,0,4+B4).B3->B10;(NOT I14,0+I5,S).B3->B11;NOT B3.B3->B12")
    memory.b[3] = 1
    memory.module(0, 5).fault[0] = 1
    executor.run_master_task()
    m = memory
    assert m.b[10:13] == [1, 1, 0]


def test_text_constants_and_bta_dem_sr0() -> None:
    executor, memory = load(
        "! M'on'->W181;M'?'->W182\n! BTA(W135)->W160[3];W161 AND H'FF00'->W176;W162->W177\n"
        "! BTA(W136)->W163[3]"
    )
    memory.w[135] = 123
    memory.w[136] = 0xFFFE
    executor.run_master_task()
    m = memory
    assert m.w[181] == ord("o") | ord("n") << 8 and m.w[182] == ord("?")
    assert m.w[160:163] == [
        ord("+") | ord("0") << 8,
        ord("0") | ord("1") << 8,
        ord("2") | ord("3") << 8,
    ]
    assert m.w[176] == ord("1") << 8 and m.w[177] == ord("2") | ord("3") << 8
    assert bytes(b for w in m.w[163:166] for b in (w & 0xFF, w >> 8)) == b"-00002"


def test_rising_and_falling_edges_dem_post() -> None:
    memory = InMemory()
    executor = Executor(parse("! IF RE(I2,B) THEN INC W1\n! IF FE(I2,B) THEN INC W2"), memory)
    seen = []
    for value in [0, 1, 1, 0, 0, 1]:
        memory.module(0, 2).i[11] = value
        executor.run_master_task()
        seen.append((memory.w[1], memory.w[2]))
    assert seen == [(0, 0), (1, 0), (1, 0), (1, 1), (1, 1), (2, 1)]


def test_an_edge_keeps_its_memory_when_both_operands_are_evaluated() -> None:
    # no short cut: RE(B11) remembers B11 even in the cycles where RE(I2,B) is true
    memory = InMemory()
    executor = Executor(
        parse("! IF NOT (RE(I2,B)+RE(B11)) THEN JUMP L1 ELSE INC W1\n!L1 :"), memory
    )
    memory.module(0, 2).i[11] = 1
    memory.b[11] = 1
    executor.run_master_task()
    memory.module(0, 2).i[11] = 0
    executor.run_master_task()
    assert memory.w[1] == 1


def test_if_then_else() -> None:
    _, m = run("! IF B1 THEN 1->W1 ELSE 2->W1;3->W2\n! IF NOT B1 THEN 4->W3")
    assert m.w[1:4] == [2, 3, 4]


def test_jump_forward_and_backward() -> None:
    _, m = run("!L1 :INC W1\n! IF [W1<5] THEN JUMP L1\n! JUMP L3\n! SET B1\n!L3 :SET B2")
    assert (m.w[1], m.b[1], m.b[2]) == (5, 0, 1)


def test_a_jump_loop_past_its_bound_is_a_fault_and_ends_the_module() -> None:
    executor, m = run("!L1 :INC W1;JUMP L1\n! SET B1\n%POST\n! SET B2")
    assert m.w[1] == MAX_JUMPS + 1 and m.b[1] == 0 and m.b[2] == 1
    assert m.sy[FAULT_BIT] == 1 and "backward JUMP" in executor.faults[0].message


def test_while_do_dem_5_3_4() -> None:
    executor, memory = load("! 0->W121\n! WHILE [W121<W120] DO INC W121;INC W122")
    memory.w[120] = 4
    executor.run_master_task()
    m = memory
    assert m.w[121:123] == [4, 4]


def test_a_while_that_does_not_end_is_a_bounded_fault() -> None:
    executor, m = run("! WHILE NOT B1 DO INC W1\n! SET B2")
    assert m.w[1] == MAX_WHILE and m.b[2] == 1
    assert "WHILE did not end within" in executor.faults[0].message


def test_call_and_ret() -> None:
    _, m = run("! CALL SR1;INC W1\n%SR1\n! INC W2\n! RET\n! INC W3")
    assert m.w[1:4] == [1, 1, 0]


def test_ret_in_the_pre_ends_it() -> None:
    _, m = run("! RET\n! SET B1\n%POST\n! SET B2")
    assert (m.b[1], m.b[2]) == (0, 1)


def test_nested_calls_are_bounded() -> None:
    executor, m = run("! CALL SR1\n%SR1\n! INC W1;CALL SR1")
    assert m.w[1] == MAX_CALL_DEPTH and "nested calls" in executor.faults[0].message


def test_text_block_exchange_and_reset_aem_scm() -> None:
    _, m = run("! H'563'->TXT0,M;H'40'->TXT0,C;68->TXT0,L;EXCHG TXT0;TXT0,D->B1;OUTPUT TXT1")
    assert m.started == [Started(0, "EXCHG", 0x563, 0x40, 68), Started(1, "OUTPUT", 0, 0, 0)]
    assert m.b[1] == 0
    m.finish(0, v=0xFE)
    assert m.text_block(0)["D"] == 1
    executor = Executor(parse("! RESET TXT1;TXT1,E->B1;TXT1,S->W1"), m)
    executor.run_master_task()
    assert (m.b[1], m.w[1]) == (1, 1)  # SCM 4.5: 1 exchange cancelled by reset


def test_exchg_on_a_busy_text_block_is_a_program_fault() -> None:
    executor, m = run("! EXCHG TXT0\n! EXCHG TXT0\n! SET B1")
    assert len(m.started) == 1 and m.b[1] == 1 and m.sy[FAULT_BIT] == 1
    assert "in progress" in executor.faults[0].message


def test_sy0_on_the_first_task_after_a_cold_restart_aem_5_1() -> None:
    memory = InMemory()
    executor = Executor(parse("! IF SY0 THEN INC W1\n! IF SY1 THEN INC W2\n! INC W3"), memory)
    executor.run_master_task()
    assert memory.sy[0] == 0 and memory.w[1:4] == [1, 0, 1]
    executor.run_master_task()
    assert memory.w[1:4] == [1, 0, 2]
    executor.hot_restart()
    executor.run_master_task()
    assert memory.w[1:4] == [1, 1, 3] and memory.sy[1] == 0  # kept on a hot restart
    memory.cw[0] = 99
    executor.cold_restart()
    assert memory.w[1:4] == [0, 0, 0] and memory.cw[0] == 99  # cleared; CW kept
    executor.run_master_task()
    assert memory.w[1:4] == [1, 0, 1]


def test_internal_bits_survive_a_hot_restart_and_not_a_cold_one() -> None:
    memory = InMemory()
    executor = Executor(parse("! IF SY0 THEN SET B5"), memory)
    executor.run_master_task()
    executor.hot_restart()
    executor.run_master_task()
    assert memory.b[5] == 1
    executor.cold_restart()
    assert memory.b[5] == 0


def test_sy7_the_minutes_bit_dem_5_3_1() -> None:
    memory = InMemory()
    executor = Executor(parse("! IF SY7.NOT B7 THEN INC W1\n! SY7->B7"), memory)
    for second in range(0, 181, 5):
        executor.run_master_task(second * 1_000_000)
    assert memory.w[1] == 3  # a rising edge of SY7 once a minute, at 30 s, 90 s, 150 s


def test_pre_chart_post_run_in_this_order() -> None:
    text = (
        "%POST\n! INC W9;W9->W12\n%PRE\n! INC W9;W9->W10\n"
        "%CHART\nCHART INITIAL 0\nCHART S(A)0\n! INC W9;W9->W11\nCHART T: 0>1\n! B1\n"
    )
    _, m = run(text)
    assert m.w[10:13] == [1, 2, 3]
