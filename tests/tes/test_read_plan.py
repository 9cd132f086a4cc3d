"""Issue 25 item 2: a TES's read plans and fused exchange answer what the reference does.

Two TES of the same model live the same random history, each behind its own TCP
session: one as the project runs it (the session's fused path, the TES's fused
exchange and read plans: ``SlaveAdapter.planned``), the other the reference (the
session's general path, ``fused = False``, and ``planned = False``: every word read
by its kind's reader, one by one).  The history: master reads of random spans by
fc 03, 04, 01 and 02 (the status and inputs at 0 that a SCADA polls first, partial
spans, spans across the start of the 32-bit area, beyond the map, quantities out of
range), master writes by fc 06 and 16 (the filter times, the status word, the
output command, the watchdog, the link counters, the 32-bit counters and
chronometers, read-only words), contacts and signals on the inputs (followed at read
time), analog levels, wiring faults on a TES 32ET-S, time, "slave not ready" (every
request, the next N, a window of each 100 ms), late answers, a deaf TES, power
cycles; through the TCP link and through a gateway to the RS-232 port.  After every step
both sent the same bytes at the same instants and hold
the same words, counters, status, memorized inputs and pending changes, LEDs and
clock events.
"""

from __future__ import annotations

import struct

from hypothesis import example, given, settings
from hypothesis import strategies as st

from fieldtwin.clock import SimClock
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import Link
from fieldtwin.modbus.session import TcpSession
from fieldtwin.signals import Edges, PulseTrain
from fieldtwin.tes import Tes
from fieldtwin.tes.execute import SlaveAdapter
from tests.tes import test_tes_lazy_inputs as lazy_inputs

_MODELS = ("32EST", "16EST", "32ET", "32ET-S", "32ST", "8EA", "4SA", "8ESA")

_start = st.one_of(
    st.just(0),
    st.integers(0, 12),
    st.integers(0x14, 0x30),  # the link counters, the start of the 32-bit area
    st.integers(0x50, 0x60),  # an analog map's 32-bit area
    st.integers(0x19C, 0x1B0),  # the end of a digital map, the TES 32ET-S words
    st.integers(0, 0x300),
    st.sampled_from((0xFFF0, 0xFFFF)),
)
_count = st.one_of(st.integers(1, 12), st.sampled_from((0, 10, 37, 125, 126)))
_read = st.tuples(st.just("read"), st.tuples(st.sampled_from((3, 3, 3, 4)), _start, _count))
_read0 = st.tuples(st.just("read"), st.tuples(st.just(3), st.just(0), st.integers(1, 10)))
_bits = st.tuples(
    st.just("read"), st.tuples(st.sampled_from((1, 2)), st.integers(0, 200), st.integers(1, 40))
)
_written = st.sampled_from(
    (0x000, 0x00A, 0x00B, 0x00C, 0x00D, 0x016, 0x017, 0x01C, 0x025, 0x026, 0x03D, 0x0A5, 0x1AB)
)
_write = st.tuples(
    st.just("write"),
    st.tuples(_written, st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=4)),
)
_filter = st.tuples(
    st.just("write"),
    st.tuples(st.sampled_from((0x00A, 0x00B)), st.lists(st.integers(0, 8), min_size=1, max_size=2)),
)
_signal = st.one_of(
    st.builds(
        PulseTrain,
        period_us=st.integers(2_000, 400_000),
        duty=st.sampled_from([0.0, 0.1, 0.5, 0.9]),
        start_us=st.integers(0, 200_000),
    ),
    st.builds(
        Edges,
        initial=st.booleans(),
        times_us=st.lists(st.integers(1, 2_000_000), max_size=8, unique=True).map(sorted),
    ),
)
_step = st.one_of(
    _read,
    _read0,
    _read0,
    _bits,
    _write,
    _filter,
    st.tuples(st.just("set"), st.tuples(st.integers(0, 31), st.booleans())),
    st.tuples(st.just("signal"), st.tuples(st.integers(0, 31), _signal)),
    st.tuples(st.just("level"), st.tuples(st.integers(0, 7), st.floats(0.0, 10.0))),
    st.tuples(st.just("advance"), st.integers(1, 60_000)),
    st.tuples(st.just("advance"), st.integers(60_000, 5_000_000)),
    st.tuples(
        st.just("fault"),
        st.sampled_from(
            ("not_ready", "not_ready_2", "window", "clear", "late", "deaf", "power", "wiring")
        ),
    ),
)


class _Rig:
    """A TES behind a TCP session: the fused paths, or the reference."""

    def __init__(self, model: str, fast: bool, link: Link = Link.TCP) -> None:
        self.clock = SimClock()
        port = Link.RS232 if link is Link.RS232 else Link.RS485
        self.tes = Tes(model, 1, clock=self.clock, link=port)
        if not fast:
            self.tes.slave_adapter.planned = False
        self.session = TcpSession([self.tes], link)
        self.session.fused = fast
        self.transaction = 0

    def request(self, pdu: bytes) -> None:
        self.transaction = (self.transaction + 1) & 0xFFFF
        self.session.receive(encode_mbap(self.transaction, 1, pdu), self.clock.now)

    def step(self, op: str, arg: object) -> None:
        tes, model = self.tes, self.tes.model
        if op == "read":
            fc, start, count = arg  # type: ignore[misc]
            self.request(struct.pack(">BHH", fc, start, count))
        elif op == "write":
            address, values = arg  # type: ignore[misc]
            if len(values) == 1:
                self.request(struct.pack(">BHH", 6, address, values[0]))
            else:
                n = len(values)
                self.request(struct.pack(f">BHHB{n}H", 16, address, n, 2 * n, *values))
        elif op == "set" and arg[0] < model.digital_inputs:  # type: ignore[index]
            tes.set_input(str(arg[0]), arg[1])  # type: ignore[index]
        elif op == "signal" and arg[0] < model.digital_inputs:  # type: ignore[index]
            tes.set_signal(str(arg[0]), arg[1])  # type: ignore[index]
        elif op == "level" and arg[0] in model.analog_inputs:  # type: ignore[index]
            tes.set_input(f"a{arg[0]}", arg[1])  # type: ignore[index]
        elif op == "advance":
            self.clock.advance(arg)  # type: ignore[arg-type]
        elif op == "fault":
            self.fault(str(arg))

    def fault(self, name: str) -> None:
        tes = self.tes
        if name == "not_ready":
            tes.set_not_ready(True)
        elif name == "not_ready_2":
            tes.set_not_ready(True, count=2)
        elif name == "window":
            tes.set_not_ready(True, window_ms=40)
        elif name == "clear":
            tes.set_not_ready(False)
            tes.set_late_answer(0)
            tes.set_no_answer(False)
        elif name == "late":
            tes.set_late_answer(3)
        elif name == "deaf":
            tes.set_no_answer(True)
        elif name == "power":
            tes.power_cycle()
        elif name == "wiring" and tes.model.safety:
            tes.set_wiring(self.clock.now % 32, ("short", "open", "ok")[self.clock.now % 3])

    def observe(self) -> object:
        tes, now = self.tes, self.clock.now
        sent = [(t.at, t.data) for t in self.session.poll(now)]
        ram = tes.ram
        tes.di.sync()
        assert tes.di.masks_agree()  # the inputs' bit masks are what they hold
        inputs = [(i.memorized, i.changes, i.filtered, i.direct) for i in tes.di._inputs]
        return (
            sent,
            self.session.next_deadline(),
            [tes.peek(a) for a in sorted(tes.registers.table)],
            {key: (list(c.values), c.not_ready_owed) for key, c in ram.counters.items()},
            ram.status,
            dict(ram.words),
            inputs,
            tes.leds,
            tes.line_faults.not_ready_left,
            self.clock.pending,
        )


def _lives(model: str, steps: list[tuple[str, object]], link: Link = Link.TCP) -> list[object]:
    rigs = [_Rig(model, fast, link) for fast in (True, False)]
    seen: list[list[object]] = [[], []]
    for op, arg in steps:
        for rig, out in zip(rigs, seen, strict=True):
            rig.step(op, arg)
            out.append((op, rig.observe()))
    assert seen[0] == seen[1]
    return seen[0]


@settings(max_examples=250, deadline=None)
@given(
    st.sampled_from(_MODELS),
    st.lists(_step, min_size=1, max_size=30),
    st.sampled_from((Link.TCP, Link.TCP, Link.RS232)),  # RS-232: a gateway to that port
)
@example("32EST", [("set", (3, True)), ("advance", 100_000), ("read", (3, 0, 10))], Link.TCP)
@example(
    "32ET",
    [
        ("set", (20, True)),
        ("advance", 50_000),
        ("set", (20, False)),
        ("advance", 50_000),
        ("read", (3, 0, 10)),
        ("read", (3, 2, 1)),
        ("read", (3, 0, 10)),
    ],
    Link.TCP,
)
@example("32EST", [("fault", "window"), ("read", (3, 0x20, 10)), ("advance", 30_000)], Link.TCP)
def test_planned_reads_answer_what_the_reference_does(
    model: str, steps: list[tuple[str, object]], link: Link
) -> None:
    _lives(model, steps, link)


def test_the_status_and_inputs_read_restores_memorized_changes() -> None:
    """What the property compares is not nothing: the read at 0 of a TES 32EST after an
    input toggled twice shows the first change, then the second (AMB-TES-12), status
    bit 3 set until both were read; the plan of 0..9 was built once."""
    steps: list[tuple[str, object]] = [
        ("set", (3, True)),
        ("advance", 100_000),
        ("set", (3, False)),
        ("advance", 100_000),
        ("read", (3, 0, 10)),
        ("read", (3, 0, 10)),
        ("read", (3, 0, 10)),
    ]
    seen = _lives("32EST", steps)
    words = [struct.unpack(">10H", out[1][0][0][1][9:]) for out in seen[4:]]
    assert [(w[0] & 8, w[1], w[3], w[5]) for w in words] == [
        (8, 1 << 3, 0, 0),  # status bit 3: changes waited; the first change shows
        (8, 0, 0, 0),  # the second
        (0, 0, 0, 0),
    ]
    rig = _Rig("32EST", True)
    for _ in range(3):
        rig.step("read", (3, 0, 10))
    assert list(rig.tes.slave_adapter._plans) == [0 * 128 + 10]


def test_the_reference_switch_is_a_class_default() -> None:
    assert SlaveAdapter.planned is True


@settings(max_examples=120, deadline=None)
@given(
    st.sampled_from(("TES 32EST", "TES 32ET-S")),
    st.lists(st.one_of(lazy_inputs._step, lazy_inputs._wiring), min_size=1, max_size=30),
)
def test_the_inputs_bit_masks_are_what_the_inputs_hold(
    model: str,
    steps: list[tuple],  # type: ignore[type-arg]
) -> None:
    """The masks the plans read (``DigitalInputs.direct_bits``...) against the inputs'
    own states after each step of the lazy inputs' histories (pulse trains whose whole
    periods are jumped, edges, filters, master reads and writes, power cycles, wiring),
    inputs followed at read time and with an event per edge; then after a master read
    of the memorized words."""
    for lazy in (True, False):
        tes = lazy_inputs._tes(model, lazy)
        for step in steps:
            if step[0] == "wiring" and not tes.model.safety:
                continue
            lazy_inputs._apply(tes, step)
            tes.di.sync()
            assert tes.di.masks_agree(), step
            tes.read(1), tes.read(2)  # memorized words: one change of each input restored
            assert tes.di.masks_agree(), step
