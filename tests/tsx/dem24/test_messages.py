"""Logging messages (DEM 4.2-2), reading them (4.2-3), the stack (2.3-4) and commands (4.2-1)."""

from __future__ import annotations

from fieldtwin.clock import S
from fieldtwin.facade import inject_fault
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.plc import Plc
from tests.tsx.dem24.helpers import SLOT, at, read, read_all, stamp, synced


def toggle(plc: Plc, mod: Dem24, channel: int, times: int, gap_s: float = 0.002) -> None:
    for _ in range(times):
        mod.set_input(channel, not mod.inputs.raw(channel))
        plc.advance(gap_s)


def test_4_2_2_change_of_state_message_layout() -> None:
    plc, mod = synced()  # 18:06:00.000 at t = 71 s
    at(plc, 71 + 1.234)
    mod.set_input(3, True)
    plc.advance(0.01)
    r = read(plc, exchange=7, count=9)
    assert r.v == 0x81 and r.s == 26 and (r.exchange, r.count) == (7, 1)
    assert r.messages[0] == [
        (1 << 8) | 7,  # messages in the exchange / exchange number
        0x0001,  # stack 0, type 0, H 0, modification indicator 1
        0x5E07,  # year 94, month 7
        0x0F12,  # day 15, hour 18
        0x0601,  # 6 min 1 s
        234,  # milliseconds
        SLOT,  # rack 0, position 4
        (3 << 8) | 1,  # channel 3 at 1
        0,
        0,
        0,
        0,
        0,
    ]


def test_4_2_2_overall_state_message_layout() -> None:
    plc, mod = synced(select=0x12_3456)
    mod.set_input(0, True)
    mod.set_input(17, True)
    plc.advance(0.01)
    read_all(plc)
    inject_fault(mod, "terminal_block", True)
    plc.write(f"OW{SLOT},1,2", 1)  # DEM 4.2-1: request logging of the overall state
    plc.advance(0.03)
    msgs = read_all(plc)
    overall = [m for m in msgs if (m[1] >> 10) & 1]
    assert len(overall) == 1
    m = overall[0]
    assert m[7:9] == [0x3456, 0x12]  # channels time-stamped
    assert m[9:11] == [0, 0]  # none oscillating
    # states at logging time: DEF = 0 forces inputs to 0 without the terminal block;
    # word 12 bit 9 = channel 25, terminal block missing (AMB-DEM-06)
    assert m[11] == 0 and m[12] == 1 << 9


def test_4_2_3_read_nine_at_a_time_oldest_first() -> None:
    plc, mod = synced()
    toggle(plc, mod, 5, 20)
    plc.advance(0.01)
    assert plc.read(f"IW{SLOT},5") == 20 and plc.read(f"I{SLOT},1") == 1
    first = read(plc, exchange=3, count=200)  # 5.3-4 asks IW4,5: at most 9 come
    assert (first.count, first.s, len(first.messages)) == (9, 234, 9)
    assert all(m[0] == (9 << 8) | 3 for m in first.messages)
    assert [m[7] & 0xFF for m in first.messages] == [1, 0, 1, 0, 1, 0, 1, 0, 1]
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},5") == 11
    second = read(plc, exchange=4, count=9)
    third = read(plc, exchange=5, count=9)
    assert (second.count, third.count, third.s) == (9, 2, 52)
    times = [stamp(m)[5:] for m in first.messages + second.messages + third.messages]
    assert times == sorted(times)
    empty = read(plc, exchange=6, count=9)
    assert (empty.v, empty.s, empty.count, empty.exchange) == (0x81, 2, 0, 6)
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},1") == 0


def test_read_fits_the_reception_table_and_loses_nothing() -> None:
    plc, mod = synced()
    toggle(plc, mod, 5, 3)
    r = plc.exchange(m=0x0400, c=0x01, send=[1, 9], recv_bytes=52)
    assert r.s == 52 and not r.e
    assert len(mod.stack) == 1  # two read, the third kept


def test_2_3_4_overflow_at_200_is_flagged_in_the_next_message() -> None:
    plc, mod = synced()
    toggle(plc, mod, 2, 205)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},5") == 200
    assert plc.read(f"I{SLOT},3") == 1 and plc.read(f"I{SLOT},2") == 1
    assert mod.leds["ERR"] == "on" and plc.read(f"IW{SLOT},0,7") == 1
    fault = plc.exchange(m=0x0463, c=0x47, recv_bytes=12)
    assert fault.data[4] & 0x02  # bit 33 stack full
    first = read(plc)
    assert all((m[1] >> 12) & 1 == 0 for m in first.messages)
    toggle(plc, mod, 2, 1)
    msgs = read_all(plc)
    assert len(msgs) == 191 + 1
    assert (msgs[-1][1] >> 12) & 1 == 1  # DEM 4.2-2 Stack = 1: at least one message lost
    assert all((m[1] >> 12) & 1 == 0 for m in msgs[:-1])
    toggle(plc, mod, 2, 1)
    (after,) = read_all(plc)
    assert (after[1] >> 12) & 1 == 0


def test_70_percent_bit() -> None:
    plc, mod = synced()
    toggle(plc, mod, 1, 139)
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},2") == 0
    toggle(plc, mod, 1, 1)
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},2") == 1 and plc.read(f"I{SLOT},3") == 0


def test_4_2_1_purge_on_a_rising_edge() -> None:
    plc, mod = synced()
    toggle(plc, mod, 1, 12)
    plc.write(f"OW{SLOT},1,1", 1)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},5") == 0
    toggle(plc, mod, 1, 2)  # bit still at 1: no new purge
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},5") == 2


def test_4_2_3_global_stop_of_logging() -> None:
    plc, mod = synced()
    plc.write(f"OW{SLOT},1,0", 1)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},2,0") == 1  # the module has accepted the command
    toggle(plc, mod, 1, 4)
    assert plc.read(f"IW{SLOT},5") == 0 and plc.read(f"IW{SLOT},6,1") == 0
    plc.write(f"OW{SLOT},1,0", 0)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},2,0") == 0
    toggle(plc, mod, 1, 1)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},5") == 1


def test_3_2_2_unselected_channels_are_plain_inputs() -> None:
    plc, mod = synced(select=0x000001)
    mod.set_input(0, True)
    mod.set_input(9, True)
    mod.set_input(20, True)
    plc.advance(0.02)
    assert plc.read(f"IW{SLOT},6") == 0x0201 and plc.read(f"IW{SLOT},7") == 0x0010
    msgs = read_all(plc)
    assert [m[7] for m in msgs] == [(0 << 8) | 1]


def test_2_5_4_and_2_5_5_logging_goes_on_in_stop_and_with_the_plc_stopped() -> None:
    plc, mod = synced()
    plc.write(f"OW{SLOT},0,C", 0)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,C") == 0
    toggle(plc, mod, 4, 3)
    plc.stop()
    toggle(plc, mod, 4, 3)
    plc.advance(1.0)
    assert len(mod.stack) == 6
    plc.start()
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},5") == 6


def test_overall_state_request_needs_a_new_rising_edge() -> None:
    plc, mod = synced()
    plc.write(f"OW{SLOT},1,2", 1)
    plc.advance(0.1)
    assert plc.read(f"IW{SLOT},5") == 1
    plc.write(f"OW{SLOT},1,2", 0)
    plc.advance(0.03)
    plc.write(f"OW{SLOT},1,2", 1)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},5") == 2


def test_nothing_is_logged_before_the_time_is_set() -> None:
    from tests.tsx.dem24.helpers import make

    plc, mod = make()
    plc.write(f"OW{SLOT},2", 0xFFFF)
    plc.advance(0.03)
    toggle(plc, mod, 0, 3)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},5") == 0 and plc.read(f"IW{SLOT},6,0") == 1
    assert plc.read(f"IW{SLOT},2,0") == 1  # no logging


def test_periodic_overall_state() -> None:
    plc, mod = synced(config=[0x0010, 0, 0, 0, 0, 0, 60, 2, 1])  # LOG, PER = 1 min
    at(plc, 71 + 60 * 3 + 0.5)
    msgs = read_all(plc)
    assert [stamp(m)[4:6] for m in msgs] == [(7, 0), (8, 0), (9, 0)]
    assert all((m[1] >> 10) & 1 for m in msgs)
    assert plc.now > 250 * S
