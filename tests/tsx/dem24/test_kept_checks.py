"""Issue 25: the DEM's kept oscillation checks and folded filter confirmations show
nothing different.

With ``Dem24.kept_checks`` an edge of an oscillating input leaves the armed check
where it is and notes where the reference re-arms it, with the sequence number the
reference's scheduling takes (the check, firing early, moves itself there); with
``InputBank.folded`` a stepped signal's edge runs its filter's confirmation inline when
nothing else is due before it.  Neither changes an instant or the order of two events:
only clock entries are saved.  Two modules live the same random history as in
test_edge_shortcuts.py (random and listed edges, some on round instants that meet the
PLC scan, the filters and the checks; configurations; reads; power breaks; floods);
the reference has every shortcut off.  After every step, and every millisecond of the
fine steps, both show the same bus face and images, words, bits, LEDs, messages,
faults, oscillation states and the instant of every channel's next check; the
messages logged are the same, in the same order, with the same stamps.
"""

from __future__ import annotations

import heapq
from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import fieldtwin.clock as clock_module
from fieldtwin.clock import MS, S
from fieldtwin.signals import Edges, RandomEdges
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.plc import Plc
from tests.tsx.dem24.test_edge_shortcuts import _outcome, _setup, _step, module_state


def _make(fast: bool) -> tuple[Plc, Dem24]:
    plc, mod = _setup(fast, kept=fast)  # every shortcut on (fast) or off
    assert mod.oscillation is not None and mod.oscillation.kept is fast
    log: list[tuple[int, int, tuple[int, ...]]] = []
    original = mod.logbook.push

    def push(message_type: Any, stamp: int, body: Any) -> bool:  # every message, when
        log.append((plc.now, stamp, tuple(body) if isinstance(body, list | tuple) else body))
        return original(message_type, stamp, body)

    mod.logbook.push = push  # type: ignore[method-assign]
    mod.pushed = log  # type: ignore[attr-defined]
    return plc, mod


def _face(plc: Plc, mod: Dem24) -> tuple[object, ...]:
    monitor = mod.oscillation
    checks = None if monitor is None else [monitor.check_at(c) for c in range(24)]
    pushed = list(mod.pushed)  # type: ignore[attr-defined]
    return (*module_state(plc, mod, checks), pushed)


@settings(max_examples=60, deadline=None)
@given(st.lists(_step, min_size=1, max_size=20))
@example([("random", (0, 3, 2_000)), ("random", (1, 4, 6_000)), ("long", 3), ("read", 30)])
@example([("config", (2, 0, 1, 2, 2, 8)), ("random", (4, 0, 2_000)), ("long", 1)])
@example([("random", (2, 5, 2_000)), ("long", 2), ("flood", 220), ("read", 30), ("long", 3)])
@example([("random", (3, 1, 6_000)), ("power", 0.3), ("random", (3, 2, 2_000)), ("long", 3)])
def test_kept_checks_and_folded_confirmations_change_nothing(steps: list[tuple[str, Any]]) -> None:
    fast, ref = _make(True), _make(False)
    assert _face(*fast) == _face(*ref)
    steps = [*steps, ("long", 3)]  # past every filter and oscillation check of the history
    for kind, arg in steps:
        for _ in range(arg if kind == "fine" else 1):  # fine: every image in between
            error = _outcome(*fast, kind, arg)
            assert error == _outcome(*ref, kind, arg), (kind, arg)
            assert _face(*fast) == _face(*ref), (kind, arg)
            if error is not None:
                return


def test_the_new_shortcuts_are_taken(monkeypatch: pytest.MonkeyPatch) -> None:
    """The same edges and messages with fewer clock entries: checks kept, not re-armed;
    confirmations run inline."""
    runs = []
    for fast in (True, False):
        plc, mod = _make(fast)
        pushed: list[object] = []

        def counted(heap: list[Any], entry: Any, pushed: list[object] = pushed) -> None:
            pushed.append(entry)
            heapq.heappush(heap, entry)

        for channel in range(6):
            mod.set_signal(channel, RandomEdges(seed=channel, mean_interval_us=20_000))
        edges0 = mod.edges_stamped
        with monkeypatch.context() as patch:
            counting = SimpleNamespace(
                heappush=counted, heappop=heapq.heappop, heapify=heapq.heapify
            )
            patch.setattr(clock_module, "heapq", counting)
            plc.advance(5.0)
        log = mod.pushed  # type: ignore[attr-defined]
        runs.append((len(pushed), mod.edges_stamped - edges0, log, mod.stack.peek()))
        assert mod.detectors is not None and sum(d.oscillating for d in mod.detectors) >= 3
    (pushes, edges, log, stack), (pushes0, edges0, log0, stack0) = runs
    assert edges == edges0 > 500 and log == log0 and stack == stack0
    assert pushes < 0.85 * pushes0, (pushes, pushes0)


def test_a_kept_check_keeps_its_order_at_a_master_task() -> None:
    """The check that ends an oscillation falls on a master task's instant, and the
    reference armed it before that task was scheduled: it runs first and the task's
    image shows its message; the kept check, moved there from an early instant 5 ms
    before, must run first too (its reserved sequence number, not a new one)."""
    faces = []
    for fast in (True, False):
        plc, mod = _make(fast)
        scan = plc._scan
        assert scan is not None
        base = scan.time + 5 * MS  # edges 5 ms off the 10 ms task grid
        times = [base + k * 5 * MS for k in range(5)]  # 4th declares, 5th kept
        mod.set_signal(0, Edges(False, times))
        plc.clock.run_until(times[3] + 2 * S - 20 * MS)
        seen = []
        for _ in range(40):  # the check at times[3] + 2 s (T-MIN 2 s, N-MIN 2)
            plc.clock.run_until(plc.now + MS)
            seen.append(_face(plc, mod))
        faces.append(seen)
        assert mod.detectors is not None and not mod.detectors[0].oscillating
    assert faces[0] == faces[1]
