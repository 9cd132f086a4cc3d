"""Grafcet evolution rules (issue 13; DEM 5.3-4 chart and macro-step XM0)."""

from __future__ import annotations

import pytest

from fieldtwin.pl7 import Executor, InMemory, Pl7Error, parse

from .helpers import load


def chart(body: str, post: str = "") -> str:
    return "%CHART\n" + body + ("\n%POST\n" + post if post else "")


def test_the_initial_step_is_active_after_the_first_task_and_runs_its_activation() -> None:
    executor, m = load(chart("CHART INITIAL 0\nCHART S(A)0\n! INC W1\nCHART T: 0>1\n! B1"))
    assert executor.active_steps() == []
    executor.run_master_task()
    executor.run_master_task()
    assert executor.active_steps() == ["0"] and m.w[1] == 1  # on activation only


def test_a_transition_fires_when_its_step_is_active_and_its_condition_true() -> None:
    executor, m = load(
        chart("CHART INITIAL 0\nCHART T: 0>1\n! B1\nCHART T: 1>2\n! B2\nCHART T: 2>0\n! B3")
    )
    executor.run_master_task()
    m.b[2] = m.b[3] = 1  # the conditions of steps not active do nothing
    executor.run_master_task()
    assert executor.active_steps() == ["0"]
    m.b[1] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["1"]  # one evolution per master task
    executor.run_master_task()
    assert executor.active_steps() == ["2"]


def test_all_firable_transitions_fire_together() -> None:
    text = chart(
        "CHART INITIAL 0,10\nCHART T: 0>1\n! B1\nCHART T: 10>11\n! B1\n"
        "CHART T: 1>2\n! B2\nCHART T: 1>3\n! B2\nCHART T: 11>10\n! B2"
    )
    executor, m = load(text)
    executor.run_master_task()
    assert executor.active_steps() == ["0", "10"]
    m.b[1] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["1", "11"]
    m.b[2] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["2", "3", "10"]  # both transitions out of 1 fired


def test_actions_on_deactivation_then_on_activation() -> None:
    text = chart(
        "CHART INITIAL 0\nCHART S(A)0\n! INC W9;W9->W1\nCHART S(D)0\n! INC W9;W9->W2\n"
        "CHART T: 0>1\n! B1\nCHART S(A)1\n! INC W9;W9->W3\nCHART S(D)1\n! INC W9;W9->W4\n"
        "CHART T: 1>0\n! B2"
    )
    executor, m = load(text)
    executor.run_master_task()
    m.b[1] = 1
    executor.run_master_task()
    assert m.w[1:4] == [1, 2, 3]  # S(D)0 before S(A)1
    m.b[2] = 1
    executor.run_master_task()
    assert m.w[1:5] == [5, 2, 3, 4]


def test_a_step_deactivated_and_activated_together_stays_active_without_actions() -> None:
    executor, m = load(
        chart("CHART INITIAL 1\nCHART S(A)1\n! INC W1\nCHART S(D)1\n! INC W2\nCHART T: 1>1\n! B1")
    )
    executor.run_master_task()
    m.b[1] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["1"] and m.w[1:3] == [1, 0]


def test_step_bits_are_readable_by_the_program() -> None:
    executor, m = load(
        chart("CHART INITIAL 0\nCHART T: 0>1\n! B1\nCHART T: 1>0\n! B2", "! X0->B10;X1->B11")
    )
    executor.run_master_task()
    assert (m.b[10], m.b[11]) == (1, 0)
    m.b[1] = 1
    executor.run_master_task()
    assert (m.b[10], m.b[11]) == (0, 1)
    assert executor.step_active("1") and not executor.step_active("0")


MACRO = (
    "CHART INITIAL M0\nCHART T: M0>0\n! B9\nCHART T: 0>M0\n! B8\n"
    "XM0 S(A) IN\n! INC W1\nXM0 T: IN>0\n! B1\nXM0 S(A) 0\n! INC W2\nXM0 S(D) 0\n! INC W3\n"
    "XM0 T: 0>OUT\n! B2\nXM0 S(A) OUT\n! INC W4\n"
)


def test_a_macro_step_enters_at_in_and_leaves_from_out_dem_xm0() -> None:
    executor, m = load(chart(MACRO, "! XM0->B20"))
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,IN"] and m.w[1] == 1 and m.b[20] == 1
    m.b[9] = 1  # the transition leaving M0 waits for OUT
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,IN"]
    m.b[1] = 1
    executor.run_master_task()
    m.b[2] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,OUT"] and m.w[2:5] == [1, 1, 1]
    executor.run_master_task()
    assert executor.active_steps() == ["0"] and m.b[20] == 0
    m.b[8] = 1
    m.b[9] = 0
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,IN"] and m.w[1] == 2


def test_cold_restart_returns_to_the_initial_situation_hot_restart_keeps_it() -> None:
    executor, m = load(chart("CHART INITIAL 0\nCHART T: 0>1\n! B1\nCHART T: 1>0\n! B2"))
    executor.run_master_task()
    m.b[1] = 1
    executor.run_master_task()
    executor.hot_restart()
    executor.run_master_task()
    assert executor.active_steps() == ["1"]
    executor.cold_restart()
    executor.run_master_task()
    assert executor.active_steps() == ["0"]


def test_a_fault_in_a_condition_makes_it_false() -> None:
    executor, m = load(chart("CHART INITIAL 0\nCHART T: 0>1\n! [W0(W1)=0]"))
    executor.run_master_task()
    m.w[1] = 9999
    executor.run_master_task()
    assert executor.active_steps() == ["0"] and executor.faults[0].module == "CHART"


def test_dem_chart_steps_through_its_phases() -> None:
    from .helpers import EXAMPLES

    memory = InMemory()
    executor = Executor(parse((EXAMPLES / "dem24_assembly.pl7").read_text()), memory)
    dem = memory.module(0, 4)
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,IN"] and dem.ow[0] >> 12 & 1 == 0
    executor.run_master_task()  # IW4,0,C = 0: the module is stopped
    assert executor.active_steps() == ["XM0,0"]
    assert memory.started[-1].m == 0x463 and memory.started[-1].c == 0x40
    memory.finish(0, v=0xFE)
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,1"] and dem.ow[0] >> 12 & 1 == 1
    dem.iw[0] |= 1 << 12  # the module runs
    executor.run_master_task()
    assert executor.active_steps() == ["XM0,2"]
    assert memory.started[-1].index == 2 and memory.started[-1].m == 0x400  # POST sets the time
    memory.finish(2, v=0xFE)
    executor.run_master_task()
    executor.run_master_task()  # IW4,5 = 0: the stack is empty
    executor.run_master_task()
    assert executor.active_steps() == ["0"]
    inputs = memory.module(0, 2).i
    for phase, (bit, expected, ow2) in enumerate(
        [(0, "1", 0xFF), (1, "2", 0xFFFF), (2, "3", 0xF000)], start=1
    ):
        inputs[bit] = 1
        executor.run_master_task()
        inputs[bit] = 0
        assert executor.active_steps() == [expected], phase
        assert dem.ow[2] == ow2
    inputs[3] = inputs[4] = 1
    executor.run_master_task()
    assert executor.active_steps() == ["4"] and (dem.ow[2], dem.ow[3]) == (0, 0xF)


def test_a_breakpoint_needs_a_chart_step() -> None:
    executor, _ = load("! RET")
    with pytest.raises(Pl7Error, match="no CHART"):
        executor.break_at_step("3")
