"""The PLC's task watchdog (issue 20 R2; docs/pl7.md "The task watchdog", manual-notes W-1).

Simulated time only: the budget is counted in operations, so every run is the same.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.pl7.executor import DEFAULT_BUDGET, OPS_PER_MS, WATCHDOG_BIT
from fieldtwin.plant import load_plant
from fieldtwin.tsx.plc import Plc

DST = "TSX DST 1635"


def nested_jumps(levels: int = 7, count: int = 100) -> str:
    """SR0..SR6 each loop ``count`` times (backward JUMP) and call the next: 100**7."""
    text = "%PRE\n!CALL SR0\n"
    for i in range(levels):
        w = 10 + i
        inner = f"!CALL SR{i + 1}\n" if i + 1 < levels else "!INC W30\n"
        text += f"%SR{i}\n!0->W{w}\n!L1: INC W{w}\n{inner}!IF [W{w}<{count}] THEN JUMP L1\n"
    return text


def nested_whiles(levels: int = 7, count: int = 100) -> str:
    """SR0..SR6 each a WHILE of ``count`` passes calling the next."""
    text = "%PRE\n!CALL SR0\n"
    for i in range(levels):
        w = 10 + i
        inner = f"CALL SR{i + 1}" if i + 1 < levels else "INC W30"
        text += f"%SR{i}\n!0->W{w}\n!WHILE [W{w}<{count}] DO INC W{w}; {inner}\n"
    return text


def spinning(plc: Plc) -> list[tuple[int, str]]:
    told: list[tuple[int, str]] = []
    plc.on_fault = lambda now, reason: told.append((now, reason))
    return told


@pytest.mark.parametrize("program", [nested_jumps(), nested_whiles()], ids=["jumps", "whiles"])
def test_a_task_past_its_budget_is_cut_and_the_plc_goes_to_fault(program: str) -> None:
    plc = Plc(scan_ms=10, speed=None)
    told = spinning(plc)
    executor = plc.load_program(program)
    plc.advance(0.01)  # the first master task
    assert plc.mode == "FAULT" and not plc.running
    assert plc.fault is not None
    assert plc.fault.startswith(f"watchdog: master task exceeded {DEFAULT_BUDGET} operations")
    assert "(150 ms)" in plc.fault and "task 1" in plc.fault
    assert plc.read(f"SY{WATCHDOG_BIT}") == 1
    assert executor.overrun is not None and executor.cycles == 1
    assert told == [(10_000, plc.fault)]
    plc.advance(1.0)  # no master task runs in the fault state; nothing told again
    assert executor.cycles == 1 and len(told) == 1 and plc.mode == "FAULT"


def test_the_budget_is_counted_in_operations_the_same_at_every_run() -> None:
    words = []
    for _ in range(2):
        plc = Plc(scan_ms=10, speed=None, watchdog_ms=10)
        executor = plc.load_program(nested_whiles())
        assert executor.budget == 10 * OPS_PER_MS
        plc.advance(0.01)
        assert plc.mode == "FAULT"
        words.append([plc.read(f"W{i}") for i in range(10, 17)] + [plc.read("W30")])
    assert words[0] == words[1] and words[0][-1] > 0  # cut at the same operation
    # a larger budget runs further before the cut
    plc = Plc(scan_ms=10, speed=None, watchdog_ms=100)
    plc.load_program(nested_whiles())
    plc.advance(0.01)
    assert plc.mode == "FAULT" and plc.read("W30") > words[0][-1]


def test_a_program_within_its_budget_runs_on() -> None:
    plc = Plc(scan_ms=10, speed=None)
    executor = plc.load_program(nested_whiles(levels=2, count=100))  # 10,000 passes
    plc.advance(0.05)
    assert plc.mode == "RUN" and plc.fault is None and executor.cycles == 5
    assert plc.read("SY11") == 0 and plc.read("W30") == 5 * 100 * 100


def test_the_loops_own_bounds_stay_program_faults() -> None:
    plc = Plc(scan_ms=10, speed=None)
    executor = plc.load_program("!L1: INC W0; JUMP L1\n")
    plc.advance(0.02)
    assert plc.mode == "RUN" and plc.read("SY18") == 1 and plc.read("SY11") == 0
    assert "backward JUMPs" in executor.faults[0].message


def test_the_discrete_outputs_fall_back_to_0() -> None:
    plc = Plc(scan_ms=10, speed=None)
    dst = plc.insert(DST, 0, 3)
    plc.load_program("%PRE\n!SET O3,2; SET O3,5\n!IF [W0>0] THEN CALL SR0\n!INC W0\n" + (
        "%SR0\n!0->W1\n!WHILE [W1<200] DO INC W1; CALL SR1\n"
        "%SR1\n!0->W2\n!WHILE [W2<200] DO INC W2; CALL SR2\n"
        "%SR2\n!0->W3\n!WHILE [W3<200] DO INC W3\n"
    ))  # fmt: skip
    plc.write("OW3,0", 0x1234)
    plc.advance(0.01)  # task 1: outputs set, no loop yet
    assert plc.mode == "RUN" and dst.o_bits == 0b100100
    plc.advance(0.01)  # task 2: the loops
    assert plc.mode == "FAULT"
    assert dst.o_bits == 0 and plc.read("O3,2") == 0  # written to the module at once
    assert plc.read("OW3,0") == 0x1234  # the register words keep their value


def test_run_is_refused_in_fault_and_a_cold_restart_is_the_way_back() -> None:
    plc = Plc(scan_ms=10, speed=None)
    executor = plc.load_program(nested_jumps())
    plc.advance(0.01)
    with pytest.raises(ConfigError, match=r"fault state \(watchdog: .*plc cold"):
        plc.start()
    assert plc.mode == "FAULT"
    plc.cold_restart()
    assert plc.mode == "RUN" and plc.fault is None and plc.read("SY11") == 0
    plc.advance(0.01)  # the same program trips again: deterministic
    assert plc.mode == "FAULT" and executor.cycles == 2


def test_a_hot_restart_lets_the_program_read_sy11() -> None:
    plc = Plc(scan_ms=10, speed=None)
    # the program spins until it sees SY11 (after a hot restart)
    plc.load_program("%PRE\n!IF SY11 THEN 1->W9; RESET SY11\n!IF [W9=0] THEN CALL SR0\n"
                     + nested_whiles().split("\n", 2)[2])  # fmt: skip
    plc.advance(0.01)
    assert plc.mode == "FAULT" and plc.read("SY11") == 1
    plc.hot_restart()
    assert plc.read("SY11") == 1  # kept over a hot restart
    plc.advance(0.05)
    assert plc.mode == "RUN" and plc.read("W9") == 1 and plc.read("SY11") == 0


def test_loading_a_program_or_a_power_cycle_ends_the_fault() -> None:
    plc = Plc(scan_ms=10, speed=None)
    plc.load_program(nested_jumps())
    plc.advance(0.01)
    executor = plc.load_program("!INC W0\n")
    assert plc.mode == "RUN"
    plc.advance(0.03)
    assert executor.cycles == 3 and plc.read("W0") == 3
    plc.load_program(nested_jumps())
    plc.advance(0.01)
    assert plc.mode == "FAULT"
    plc.power_break(0.005)  # within the power reserve: the PLC never stopped
    assert plc.mode == "FAULT"
    plc.power_break(1.0)  # a power cycle: the PLC starts again (SY1, SY11 kept)
    assert plc.mode == "RUN" and plc.read("SY11") == 1


def test_the_console_says_why(tmp_path: Path) -> None:
    (tmp_path / "spin.pl7").write_text(nested_whiles())
    plant_file = tmp_path / "plant.toml"
    plant_file.write_text('[plc]\nprogram = "spin.pl7"\n')
    plant = load_plant(plant_file)
    console = Console(plant)
    console.execute("advance 10ms")
    status = console.execute("status")
    assert status[0].startswith("PLC TSX 87 FAULT")
    assert status[1].startswith("fault: watchdog: master task exceeded 150000 operations")
    assert console.execute("read SY11")[0].endswith("1")
    assert "PLC in FAULT, watchdog" in console.execute("prog show")[0]
    with pytest.raises(ConfigError, match="plc cold"):
        console.execute("plc run")
    assert console.execute("plc cold") == ["PLC RUN (cold restart)"]


def test_the_trip_is_an_event_of_the_plant(tmp_path: Path) -> None:
    (tmp_path / "spin.pl7").write_text(nested_jumps())
    plant_file = tmp_path / "plant.toml"
    plant_file.write_text('[plc]\nprogram = "spin.pl7"\nwatchdog_ms = 20\n')
    plant = load_plant(plant_file)
    sub = plant.events.subscribe(kinds=("plc",))
    assert plant.plc is not None
    plant.plc.advance(0.05)
    events = sub.take()
    assert [(e.kind, e.device, e.t_us) for e in events] == [("plc", "plc", 10_000)]
    assert events[0].data["mode"] == "FAULT"
    assert "exceeded 20000 operations (20 ms)" in str(events[0].data["fault"])


@pytest.mark.parametrize("value", [5, 501, True, "150"])
def test_the_watchdog_period_of_a_plant_is_bounded(tmp_path: Path, value: object) -> None:
    plant_file = tmp_path / "plant.toml"
    shown = f'"{value}"' if isinstance(value, str) else str(value).lower()
    plant_file.write_text(f"[plc]\nwatchdog_ms = {shown}\n")
    with pytest.raises(ConfigError, match=r"plc\.watchdog_ms: .* \(allowed 10\.\.500 ms\)"):
        load_plant(plant_file)
