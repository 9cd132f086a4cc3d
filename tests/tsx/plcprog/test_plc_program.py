"""The PLC's execution model with a program: objects, restarts, run-time faults (issue 13)."""

from __future__ import annotations

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.pl7 import FAULT_BIT, Pl7Error
from fieldtwin.tsx.plc import Plc

COUNTER = """\
%PRE
!     IF SY0 THEN SET B1
!     IF SY1 THEN SET B2
!     INC W12
!     W12->W13
"""


def test_internal_objects_read_and_written_by_name() -> None:
    plc = Plc()
    plc.load_program(COUNTER)
    plc.advance(0.1)  # ten master tasks of 10 ms
    assert plc.read("W12") == 10 and plc.read("W13") == 10
    assert plc.read("B1") == 1 and plc.read("B2") == 0 and plc.read("SY0") == 0
    plc.write("W20", 5)
    plc.write("B3", 1)
    plc.write("W21,3", 1)
    plc.write("CW7", 0x1234)
    assert (plc.read("W20"), plc.read("B3"), plc.read("W21"), plc.read("CW7")) == (5, 1, 8, 0x1234)
    with pytest.raises(ConfigError, match="B4096"):
        plc.read("B4096")
    with pytest.raises(ConfigError, match="is a bit"):
        plc.write("B3", 2)
    with pytest.raises(ConfigError, match="no program with a chart"):
        plc.read("X2")


def test_hot_restart_keeps_internal_objects_cold_restart_clears_them() -> None:
    plc = Plc()
    plc.load_program(COUNTER)
    plc.advance(0.05)
    plc.write("B1", 0)
    plc.hot_restart()  # SY1 for one task; W12 kept
    plc.advance(0.01)
    assert plc.read("B2") == 1 and plc.read("B1") == 0 and plc.read("W12") == 6
    plc.cold_restart()  # SY0; B and W cleared, CW kept
    plc.write("CW3", 9)
    plc.advance(0.01)
    assert plc.read("B2") == 0 and plc.read("B1") == 1 and plc.read("W12") == 1
    assert plc.read("CW3") == 9


def test_a_power_break_beyond_the_reserve_is_a_hot_restart_a_short_one_is_not() -> None:
    plc = Plc()
    plc.load_program(COUNTER)
    plc.advance(0.05)
    plc.power_break(0.005)  # within the 10 ms reserve: the program never notices
    plc.advance(0.01)
    assert plc.read("B2") == 0
    counted = plc.read("W12")
    plc.power_break(1.0)  # the reserve is exhausted: a hot restart on power return
    plc.advance(0.01)
    assert plc.read("B2") == 1  # SY1 was 1 during the first master task
    assert plc.read("B1") == 1 and plc.read("W12") == counted + 1  # internal objects kept
    assert plc.read("SY1") == 0  # reset by the system at the end of that task


def test_stop_holds_the_program() -> None:
    plc = Plc()
    plc.load_program(COUNTER)
    plc.advance(0.03)
    plc.stop()
    plc.advance(0.05)
    assert plc.read("W12") == 3
    plc.start()
    plc.advance(0.01)
    assert plc.read("W12") == 4


def test_a_run_time_fault_sets_the_system_bit_and_the_run_goes_on() -> None:
    plc = Plc()
    plc.load_program("%PRE\n!     200->W1\n!     W4000(W1)->W2\n!     INC W3\n")
    plc.advance(0.03)
    assert plc.read("W3") == 3 and plc.read(f"SY{FAULT_BIT}") == 1
    assert plc.program is not None and "past the table" in str(plc.program.faults[-1])


def test_a_text_block_started_twice_is_a_program_fault_not_an_end() -> None:
    plc = Plc()
    plc.insert("TSX AEM 811", 0, 5)
    text = "%PRE\n!     H'563'->TXT0,M;H'47'->TXT0,C;EXCHG TXT0;INC W3\n"
    plc.load_program(text)
    plc.advance(0.05)
    assert plc.read("W3") >= 1 and plc.read(f"SY{FAULT_BIT}") == 1
    assert plc.program is not None and "in progress" in str(plc.program.faults[-1])


def test_a_refused_program_names_line_column_and_token() -> None:
    plc = Plc()
    with pytest.raises(Pl7Error) as info:
        plc.load_program("%PRE\n!     0->CW1\n", source="bad.pl7")
    assert info.value.line == 2 and "CW1" in str(info.value) and "bad.pl7" in str(info.value)
    assert plc.program is None
