"""Sampling in simulated time: AEM 2.2-4, 3.2-1 and 4.1-4."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.tsx.aem811.sequencer import SLOT_US, Sequencer
from tests.tsx.aem811.helpers import CHN, at, configure, ready, run, until


def test_4_1_4_normal_mode_register_timing() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=1.0)
    mod.set_input(4, volts=4.0)
    t = run(plc, mod)  # default configuration: P = 10 x 100 ms
    until(plc, at(t, 99.999))
    assert mod.iw[3] == 0
    until(plc, at(t, 100))  # 100 ms after the acquisition of channel 0
    assert (mod.iw[3], mod.iw[2] & 1) == (1000, 0)
    until(plc, at(t, 499.999))  # held 400 ms
    assert (mod.iw[3], mod.iw[2] & 1) == (1000, 0)
    until(plc, at(t, 500))
    assert (mod.iw[3], mod.iw[2] & 1) == (4000, 1)
    until(plc, at(t, 1099.999))  # channel 4 held P - 400 ms
    assert (mod.iw[3], mod.iw[2] & 1) == (4000, 1)
    until(plc, at(t, 1100))
    assert (mod.iw[3], mod.iw[2] & 1) == (1000, 0)
    plc.advance(0.02)
    assert plc.read("IW5,3") == 1000 and plc.read("IW5,2,0") == 0


def test_value_sampled_when_its_slot_begins() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=1.0)
    t = run(plc, mod)
    until(plc, at(t, 50))
    mod.set_input(0, volts=2.0)  # after channel 0 was sampled
    until(plc, at(t, 100))
    assert mod.iw[3] == 1000
    until(plc, at(t, 1100))
    assert mod.iw[3] == 2000


def test_3_2_1_period_is_honoured() -> None:
    plc, mod = ready()
    configure(plc, [0x00A0, 50])  # 5 s
    t = run(plc, mod)
    until(plc, t + 50 * S - 1)
    assert mod.relay_operations == [10] * 8
    until(plc, t + 50 * S)
    assert mod.relay_operations[0] == 11 and mod.relay_operations[1] == 10


def test_2_2_4_inhibited_channel_is_a_wait() -> None:
    plc, mod = ready(quantize=False)
    for ch in range(8):
        mod.set_input(ch, volts=ch + 1)
    plc.write("OW5,1", 1 << 5)  # channel 5 inhibited
    t = run(plc, mod)
    assert plc.read("IW5,1,5") == 1  # mirrored
    until(plc, at(t, 800))
    assert mod.iw[4] == 2000 and mod.iw[2] >> 1 & 1 == 0  # only channel 1 in IWxy,4
    assert mod.iw[5] == 7000 and mod.iw[2] >> 2 & 1 == 1  # channel 6 still at 600..700
    assert mod.relay_operations[5] == 0 and mod.relay_operations[6] == 1
    until(plc, at(t, 1700))
    assert mod.iw[4] == 2000


def test_inhibiting_a_displayed_channel() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(1, volts=1.5)
    mod.set_input(5, volts=5.5)
    t = run(plc, mod)
    until(plc, at(t, 650))
    assert mod.iw[4] == 5500
    plc.write("OW5,1", 1 << 5)
    plc.advance(0.02)
    assert mod.iw[4] == 1500 and mod.iw[2] >> 1 & 1 == 0  # AMB-AEM-20
    plc.write("OW5,1", (1 << 5) | (1 << 1))
    plc.advance(0.02)
    assert mod.iw[4] == 0  # both inhibited: forced to 0


def test_4_1_4_accelerated_mode() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=1.0)
    mod.set_input(1, volts=2.0)
    plc.write("OW5,1", 0x1FC)  # OWxy,1,8 accelerated, channels 0 and 1 enabled
    t = run(plc, mod)
    until(plc, at(t, 100))
    assert mod.iw[3] == 1000
    until(plc, at(t, 150))
    mod.set_input(0, volts=3.0)
    until(plc, at(t, 200))
    assert mod.iw[4] == 2000
    until(plc, at(t, 300))  # channel 0 sampled again at 200, n x 100 ms later
    assert mod.iw[3] == 3000
    until(plc, t + 10 * S - 1)
    assert mod.relay_operations[:3] == [50, 50, 0]


def test_accelerated_same_register_alternates_every_100_ms() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=1.0)
    mod.set_input(4, volts=4.0)
    plc.write("OW5,1", 0x1EE)  # channels 0 and 4
    t = run(plc, mod)
    seen = []
    for k in range(1, 5):
        until(plc, at(t, 100 * k))
        seen.append((mod.iw[3], mod.iw[2] & 1))
    assert seen == [(1000, 0), (4000, 1), (1000, 0), (4000, 1)]


def test_switching_modes_while_running() -> None:
    plc, mod = ready()
    t = run(plc, mod)
    until(plc, at(t, 850))  # normal mode, waiting for the next cycle at 1000
    plc.write("OW5,1,8", 1)
    plc.advance(0.05)
    assert mod.relay_operations[0] == 2  # accelerated starts at once
    plc.write("OW5,1,8", 0)
    plc.advance(3)
    assert all(n > 2 for n in mod.relay_operations)


def test_4_2_read_measurements_from_one_cycle() -> None:
    plc, mod = ready(quantize=False)
    for ch in range(8):
        mod.set_input(ch, volts=ch - 3.5)
    plc.write("OW5,1,2", 1)
    t = run(plc, mod)
    until(plc, at(t, 850))
    for ch in range(8):
        mod.set_input(ch, volts=9.0)
    r = plc.exchange(m=CHN, c=1, recv_bytes=16)
    assert (r.v, r.s, r.e) == (0x81, 16, False)
    values = [w - 0x10000 if w & 0x8000 else w for w in r.words]
    assert values == [-3500, -2500, 0, -500, 500, 1500, 2500, 3500]
    until(plc, at(t, 1850))
    r = plc.exchange(m=CHN, c=1, recv_bytes=16)
    assert r.words == [9000, 9000, 0, 9000, 9000, 9000, 9000, 9000]


def test_stop_keeps_the_last_values() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=1.0)
    t = run(plc, mod)
    until(plc, at(t, 150))
    plc.write("OW5,0,C", 0)
    mod.set_input(0, volts=7.0)
    plc.advance(5)
    assert plc.read("IW5,3") == 1000 and plc.read("IW5,0,C") == 0
    r = plc.exchange(m=CHN, c=1, recv_bytes=16)
    assert r.v == 0x81  # AEM 4.2-1: works in Stop too


@given(
    st.integers(8, 40),
    st.integers(0, 255),
    st.booleans(),
    st.integers(0, 5 * S),
)
def test_sequencer_slots_on_the_grid(period: int, mask: int, accelerated: bool, now: int) -> None:
    seq = Sequencer(period * SLOT_US, accelerated, 0)
    slot = seq.next_slot(now, mask)
    if mask == 0:
        assert slot is None
        return
    assert slot is not None and mask >> slot.channel & 1 and slot.start >= now
    if not accelerated:
        assert (slot.start - slot.channel * SLOT_US) % (period * SLOT_US) == 0
    else:
        assert slot.start == now
    seq.begin(slot)
    after = seq.next_slot(slot.start + SLOT_US, mask)
    assert after is not None and after.start >= slot.start + SLOT_US


def test_sequencer_normal_cycle_order() -> None:
    seq = Sequencer(10 * SLOT_US, False, 0)
    order = []
    now = 0
    for _ in range(7):
        slot = seq.next_slot(now, 0b10100101)
        assert slot is not None
        seq.begin(slot)
        order.append((slot.start // MS, slot.channel, slot.cycle_ended))
        now = slot.start + SLOT_US
    assert order == [
        (0, 0, False), (200, 2, False), (500, 5, False), (700, 7, False),
        (1000, 0, True), (1200, 2, False), (1500, 5, False),
    ]  # fmt: skip
