"""Issue 25 item 4: the DEM's shortcuts in the 32-DEM rack's settings show nothing different.

``benchmarks/dem_rack.py`` runs modules that log with FILT 10 ms beside a 10 ms master
task, several on one synchronization output, their messages read every second.  Two
PLCs live the same random history: in one every DEM shortcut is on (``Dem24.shortcuts``
with the fused logging of an edge, ``kept_checks``, ``InputBank.stepped``, ``folded``
and ``lazy_stamps``), in the other every one is off (the reference).  Three modules,
the first driving the IN-SYN of the two others; random and listed edges (some on the
master task's 10 ms grid, where the confirmation meets the refresh), pulses, drifts of
the module clock, reads through the API and through the Text Block, global stop and
selection.  After every step, and every millisecond of the fine steps, both show the
same PLC images of every slot, words, bits, LEDs, stacks, fault latches, and the same
messages offered to each logbook, with the instant they were offered and their stamps,
in order.
"""

from __future__ import annotations

from typing import Any

from hypothesis import example, given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.signals import Edges, RandomEdges
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.plc import Plc

MODULES = 3
CONFIG = [0x0010, 10, 0, 0, 0, 0, 30, 10, 1]  # LOG, FILT 10 ms, T-SYN 30 s, PER 1 min
TIME = [0x5E07, 0x0F12, 0x0521, 0x0001]  # DEM 4.1-2 example: 15 July 1994 18:05:33


def _m(module: Dem24, zz: int) -> int:
    return (module.rack << 12) | (module.slot << 8) | zz


def _build(fast: bool) -> tuple[Plc, list[Dem24]]:
    plc = Plc(model="TSX 87", scan_ms=10)
    mods: list[Dem24] = []
    for k in range(MODULES):
        module = plc.insert("TSX DEM 2412", rack=0, slot=k + 1, code=777)
        assert isinstance(module, Dem24)
        if not fast:
            module.shortcuts = False
            module.kept_checks = False
            module.inputs.stepped = False
            module.inputs.folded = False
            module.inputs.lazy_stamps = False
        log: list[tuple[int, int, object]] = []

        def push(message_type: Any, stamp: int, body: Any, module: Dem24 = module) -> bool:
            module.pushed.append((plc.now, stamp, tuple(body)))  # type: ignore[attr-defined]
            return module.logbook.__class__.push(module.logbook, message_type, stamp, body)

        module.pushed = log  # type: ignore[attr-defined]
        module.logbook.push = push  # type: ignore[method-assign]
        mods.append(module)
    for other in mods[1:]:
        mods[0].connect_sync_output(other)
    plc.advance(10.1)
    for module in mods:
        assert plc.exchange(m=_m(module, 0x63), c=0x40, send=CONFIG).v == 0xFE
        plc.write(f"OW{module.address},0,C", 1)
        plc.write(f"OW{module.address},2", 0x000F)
    mods[0].attach_pulse_source(30 * S, plc.now + 5 * S)
    for module in mods:
        plc.exchange(m=_m(module, 0x00), c=0x02, send=TIME)
    plc.advance(40.0)
    assert all(m.logbook.timebase.ready for m in mods)
    return plc, mods


def _face(plc: Plc, mods: list[Dem24]) -> tuple[object, ...]:
    faces: list[object] = [plc.now, plc.cycles]
    for module in mods:
        latches = {
            b: (f.active, f.latched, f.acknowledged) for b, f in module._faults._latches.items()
        }
        stack = module.stack
        faces.append(
            (
                plc.image(module.rack, module.slot),
                module.bus_read(),
                list(module.iw),
                module.i_bits,
                module.leds,
                module.edges_stamped,
                stack.peek(),
                (stack.lost, stack.total_lost, stack.total_stored),
                latches,
                list(module.pushed),  # type: ignore[attr-defined]
            )
        )
    return tuple(faces)


_module = st.integers(0, MODULES - 1)
_channel = st.integers(0, 5)  # 0..3 selected, 4..5 not
_grid = st.integers(1, 60).map(lambda k: k * 10 * MS)  # on the master task's grid
_near = st.integers(1, 60).map(lambda k: k * 10 * MS + 1)
_edge_times = st.lists(st.one_of(st.integers(1, 300_000), _grid, _near), max_size=10)
_step = st.one_of(
    st.tuples(st.just("advance"), st.integers(1, 400_000)),
    st.tuples(st.just("fine"), st.integers(1, 30)),
    st.tuples(st.just("long"), st.integers(1, 2)),
    st.tuples(
        st.just("random"),
        st.tuples(_module, _channel, st.integers(0, 99), st.sampled_from([15_000, 40_000])),
    ),
    st.tuples(st.just("edges"), st.tuples(_module, _channel, st.booleans(), _edge_times)),
    st.tuples(st.just("read"), st.tuples(_module, st.integers(0, 20))),
    st.tuples(st.just("read_all"), st.just(0)),
    st.tuples(st.just("ow1"), st.tuples(_module, st.integers(0, 7))),
    st.tuples(st.just("select"), st.tuples(_module, st.integers(0, 0xFFFF))),
    st.tuples(st.just("pulse"), st.just(0)),
    st.tuples(st.just("read_txt"), _module),
    st.tuples(st.just("drift"), st.tuples(_module, st.sampled_from([-20.0, 0.0, 25.0, 200_000.0]))),
)


def _apply(plc: Plc, mods: list[Dem24], kind: str, arg: Any) -> None:
    if kind == "advance":
        plc.clock.run_until(plc.now + arg)
    elif kind == "fine":
        plc.clock.run_until(plc.now + MS)
    elif kind == "long":
        plc.advance(float(arg))
    elif kind == "random":
        k, channel, seed, mean = arg
        mods[k].set_signal(channel, RandomEdges(seed=seed, mean_interval_us=mean))
    elif kind == "edges":
        k, channel, initial, gaps = arg
        scan = plc._scan
        base = plc.now if scan is None else scan.time  # the next master task's instant
        times, t = [], base
        for gap in gaps:
            t += gap
            times.append(t)
        mods[k].set_signal(channel, Edges(initial, times))
    elif kind == "read":
        k, count = arg
        mods[k].read_messages(count)
    elif kind == "read_all":
        for module in mods:
            module.read_messages(len(module.stack))
    elif kind == "ow1":
        k, value = arg
        plc.write(f"OW{mods[k].address},1", value)
    elif kind == "select":
        k, value = arg
        plc.write(f"OW{mods[k].address},2", value)
    elif kind == "pulse":
        mods[0].sync_pulse()  # OUT-SYN repeats it to the others
    elif kind == "drift":  # the module clock moves: stamps left to compute are fixed first
        k, ppm = arg
        mods[k].set_clock_drift(ppm)
    elif kind == "read_txt":
        plc.exchange(m=_m(mods[arg], 0x00), c=0x01, send=[1, 9], recv_bytes=234)


@settings(max_examples=60, deadline=None)
@given(st.lists(_step, min_size=1, max_size=15))
@example([("random", (0, 0, 1, 15_000)), ("random", (1, 1, 2, 15_000)), ("long", 2)])
@example([("edges", (1, 2, False, [10 * MS, 30 * MS, 60 * MS])), ("fine", 30), ("read_all", 0)])
@example([("random", (2, 3, 5, 15_000)), ("pulse", 0), ("fine", 20), ("read_txt", 2)])
@example([("edges", (0, 1, False, [5 * MS, 10 * MS + 1])), ("drift", (0, 200_000.0)), ("long", 1)])
@example([("ow1", (0, 1)), ("random", (0, 0, 1, 15_000)), ("select", (1, 0x30))])
@example([("random", (1, 4, 7, 15_000)), ("random", (1, 2, 8, 40_000)), ("read", (1, 3))])
def test_the_rack_shortcuts_change_nothing(steps: list[tuple[str, Any]]) -> None:
    fast, ref = _build(True), _build(False)
    assert _face(*fast) == _face(*ref)
    for kind, arg in [*steps, ("long", 1)]:
        for _ in range(arg if kind == "fine" else 1):
            _apply(*fast, kind, arg)
            _apply(*ref, kind, arg)
            assert _face(*fast) == _face(*ref), (kind, arg)


def test_a_drift_between_an_edge_and_its_confirmation() -> None:
    """The module clock drifts after an edge and before its confirmation: the message
    carries the clock's reading at the edge as it was then (the lazy stamp is fixed
    before the drift), as the reference stamps it at the edge."""
    faces = []
    for fast in (True, False):
        plc, mods = _build(fast)
        t0 = plc.now + 3 * MS + 7
        mods[0].set_signal(1, Edges(False, [t0]))
        plc.clock.run_until(t0 + 5 * MS)  # between the edge and its confirmation
        mods[0].set_clock_drift(200_000.0)  # 20 %: 5 ms of module time become 6
        plc.advance(1.0)
        faces.append(_face(plc, mods))
        assert mods[0].pushed[-1][2][0] == 0x0101  # type: ignore[attr-defined]  # channel 1 on
    assert faces[0] == faces[1]
