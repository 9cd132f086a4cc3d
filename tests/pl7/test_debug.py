"""Step-by-step debugging: stop at a label or a step, run one master task."""

from __future__ import annotations

import pytest

from fieldtwin.pl7 import Pl7Error

from .helpers import load


def test_a_label_breakpoint_holds_after_the_task_that_reached_it() -> None:
    executor, m = load("! INC W1\n! IF B1 THEN JUMP L5\n! RET\n!L5 :INC W2")
    executor.break_at_label("PRE", 5)
    assert executor.run_master_task() and executor.held is None
    m.b[1] = 1
    assert executor.run_master_task()
    assert executor.held is not None and str(executor.held) == "PRE L5 reached in task 2"
    assert m.w[1:3] == [2, 1]  # the task ran to its end
    assert not executor.run_master_task() and m.w[1] == 2  # held
    executor.step()
    assert m.w[1] == 3 and executor.held is not None  # one task, then held again
    executor.clear_breakpoints()
    executor.resume()
    assert executor.run_master_task() and m.w[1] == 4


def test_a_step_breakpoint_holds_when_the_step_becomes_active() -> None:
    executor, m = load("%CHART\nCHART INITIAL 0\nCHART T: 0>1\n! B1\nCHART T: 1>0\n! B2")
    executor.break_at_step("1")
    executor.run_master_task()
    m.b[1] = 1
    executor.run_master_task()
    assert executor.held is not None and executor.held.step == "1"
    assert executor.hits[-1].cycle == 2


def test_unknown_breakpoints_are_refused() -> None:
    executor, _ = load("!L1 :RET\n%CHART\nCHART INITIAL 0\nCHART T: 0>1\n! B1")
    with pytest.raises(Pl7Error, match="PRE L2"):
        executor.break_at_label("PRE", 2)
    with pytest.raises(Pl7Error, match="step of the chart: 0, 1"):
        executor.break_at_step("7")


def test_the_package_is_sans_io() -> None:
    from pathlib import Path

    import fieldtwin.pl7

    package = Path(fieldtwin.pl7.__file__).parent
    for path in package.glob("*.py"):
        text = path.read_text()
        for name in ("asyncio", "socket", "serial", "time", "datetime", "selectors"):
            assert f"import {name}\n" not in text and f"from {name} " not in text, path


def test_a_cold_restart_clears_the_fault_bit() -> None:
    executor, m = load("! 1/W1->W2")
    executor.run_master_task()
    assert m.sy[18] == 1 and len(executor.faults) == 1
    executor.cold_restart()
    assert m.sy[18] == 0 and not executor.faults


def test_the_python_block_of_docs_pl7_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    page = (root / "docs" / "pl7.md").read_text()
    blocks = re.findall(r"^```python\n(.*?)^```", page, re.S | re.M)
    assert blocks
    monkeypatch.chdir(root)
    for block in blocks:
        exec(compile(block, "docs/pl7.md", "exec"), {})
