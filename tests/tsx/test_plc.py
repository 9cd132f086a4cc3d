"""The PLC: models, slots, the bus refresh and Text Block timing and error codes."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.plc import MODELS, ExchangeTimeout, Plc
from tests.tsx.double import DOUBLE, Double

SCAN = 10_000  # us


def make(model: str = "TSX 87", slot: int = 3) -> tuple[Plc, Double]:
    plc = Plc(model=model, scan_ms=10)
    mod = plc.insert(DOUBLE, rack=0, slot=slot)
    plc.advance(2.1)
    return plc, mod


def m_of(slot: int, zz: int = 0x63) -> int:
    return (slot << 8) | zz


@pytest.mark.parametrize("model", list(MODELS))
def test_immediate_answer_is_reported_one_cycle_after_validation(model: str) -> None:
    # AEM 4.2-2: validated at the end of the master task; access time 1 master task cycle
    plc, _ = make(model)
    start = plc.now
    tb = plc.start_exchange(m=m_of(3), c=0x0F, recv_bytes=27)
    plc.advance(0.005)
    assert not tb.done
    validated = (start // SCAN + 1) * SCAN
    plc.advance((validated - plc.now) / 1e6)
    assert not tb.done  # validated now, answered, not yet reported
    plc.advance(SCAN / 1e6)
    assert tb.done and tb.result is not None
    assert tb.result.ended_at_us == validated + SCAN
    assert tb.result.report_name == MODELS[model].report_name


def test_late_answer_is_reported_at_the_first_cycle_end_after_it() -> None:
    plc, _ = make()
    r = plc.exchange(m=m_of(3), c=0x01, send=[0x1234, 0x5678], recv_bytes=4)
    assert r.words == [0x1234, 0x5678] and r.v == 0x81 and r.s == 4
    assert r.ended_at_us % SCAN == 0


def test_report_is_R_on_a_47_20_and_V_elsewhere() -> None:
    plc, _ = make("TSX 47-20")
    r = plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27)
    assert r.report_name == "R" and r.r == 0x3F and "TXT,R = H'003F'" in str(r)
    plc87, _ = make("TSX 87")
    assert "TXT,V = H'003F'" in str(plc87.exchange(m=m_of(3), c=0x0F, recv_bytes=27))


def test_table_longer_than_30_bytes_on_a_47_20_is_error_2() -> None:
    # SCM 4.1: tables of 30 characters on a TSX 47-20; SCM 4.5: 2 = table length error
    plc, _ = make("TSX 47-20")
    r = plc.exchange(m=m_of(3), c=0x49, send_bytes=b"x" * 31)
    assert r.e and r.s == 2
    ok = plc.exchange(m=m_of(3), c=0x49, send_bytes=b"x" * 20)
    assert not ok.e
    r87 = make("TSX 87")[0].exchange(m=m_of(3), c=0x01, send_bytes=b"y" * 200, recv_bytes=200)
    assert not r87.e and r87.s == 200


def test_47_20_takes_intelligent_modules_in_its_first_four_slots_only() -> None:
    plc = Plc(model="TSX 47-20")
    with pytest.raises(ConfigError, match="slot 4 cannot take an intelligent module"):
        plc.insert(DOUBLE, rack=0, slot=4)
    with pytest.raises(ConfigError, match="rack 1 out of range"):
        plc.insert(DOUBLE, rack=1, slot=0)


def test_47_30_basic_rack_takes_five_intelligent_modules() -> None:
    # AEM 6.1-1: "Basic configuration TSX 47 30 (single rack): any slot, 5 intelligent
    # modules max."
    plc = Plc(model="TSX 47-30")
    for slot in range(5):
        plc.insert(DOUBLE, rack=0, slot=slot)
    with pytest.raises(ConfigError, match="at most 5 intelligent modules"):
        plc.insert(DOUBLE, rack=0, slot=5)
    plc.insert(DOUBLE, rack=1, slot=0)  # an extension rack: any slot


def test_47_20_refreshes_register_words_every_second_cycle() -> None:
    # AEM 2.4-3: register words updated on every second cycle of a TSX 47-20
    plc, mod = make("TSX 47-20")
    seen = []
    plc.write("OW3,1", 0x00AA)
    for _ in range(6):
        plc.advance(0.01)
        seen.append(plc.read("IW3,1"))
    changes = [i for i in range(1, len(seen)) if seen[i] != seen[i - 1]]
    assert len(set(seen)) == 2 and seen[-1] == 0x00AA
    plc87, _ = make("TSX 87")
    plc87.write("OW3,1", 0x00AA)
    plc87.advance(0.01)
    assert plc87.read("IW3,1") == 0x00AA
    assert changes


def test_discrete_bits_every_cycle_and_outputs() -> None:
    plc, mod = make()
    plc.write("OW3,1", 0b101)
    plc.advance(0.01)
    assert plc.read("I3,0") == 1 and plc.read("I3,1") == 0 and plc.read("I3,2") == 1
    plc.write("O3,3", 1)
    plc.advance(0.01)
    assert mod.o_bits == 0b1000 and plc.read("O3,3") == 1
    with pytest.raises(ConfigError, match=r"discrete outputs O,0\.\.O,3"):
        plc.write("O3,4", 1)
    with pytest.raises(ConfigError, match="is an input"):
        plc.write("IW3,0", 1)
    with pytest.raises(ConfigError, match="is a bit"):
        plc.write("OW3,0,C", 2)


def test_error_5_for_an_empty_slot_or_a_bad_channel() -> None:
    plc, _ = make()
    assert plc.exchange(m=m_of(6), c=0x0F, recv_bytes=27).s == 5
    r = plc.exchange(m=m_of(3, 0x05), c=0x0F, recv_bytes=27)
    assert r.e and r.s == 5 and r.error_text is not None and "parameter" in r.error_text


def test_error_4_for_a_removed_module() -> None:
    plc, _ = make()
    plc.remove(0, 3)
    r = plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27)
    assert r.e and r.s == 4


def test_error_5_for_a_second_exchange_on_a_busy_channel() -> None:
    plc, mod = make()
    plc.start_exchange(m=m_of(3), c=0x02, txt=0)
    plc.advance(0.02)
    r = plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27, txt=1)
    assert r.e and r.s == 5


def test_error_6_for_an_answer_longer_than_the_reception_table() -> None:
    plc, _ = make()
    r = plc.exchange(m=m_of(3), c=0x03, recv_bytes=10)
    assert r.e and r.s == 6


def test_error_3_for_a_power_break_during_the_exchange() -> None:
    plc, _ = make()
    tb = plc.start_exchange(m=m_of(3), c=0x02)
    plc.advance(0.02)
    plc.power_break(0.5)
    assert tb.done and tb.result is not None and tb.result.e and tb.result.s == 3


def test_error_1_when_the_text_block_is_reset() -> None:
    plc, mod = make()
    tb = plc.start_exchange(m=m_of(3), c=0x02)
    plc.advance(0.02)
    plc.reset_text_block(0)
    assert tb.result is not None and tb.result.e and tb.result.s == 1
    assert mod.pending_exchange(0x63) is None


def test_error_10_for_an_indirect_table_address_out_of_memory() -> None:
    plc, _ = make()
    plc.write("W10", 60000)
    r = plc.exchange(m=m_of(3), c=0x01, indirect=10, length=4, recv_bytes=4)
    assert r.e and r.s == 10
    plc.write("W10", 200)
    plc.write("W200", 0x4142)
    plc.write("W201", 0x4344)
    r = plc.exchange(m=m_of(3), c=0x01, indirect=10, length=4, recv_bytes=4)
    assert not r.e and r.words == [0x4142, 0x4344]


def test_direct_table_receives_the_words() -> None:
    plc, _ = make()
    plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27, table=100)
    assert plc.read("W100") == ord("T") | ord("E") << 8


def test_exchange_bound() -> None:
    plc, _ = make()
    with pytest.raises(ExchangeTimeout, match=r"not ended after 1\.0 simulated seconds"):
        plc.exchange(m=m_of(3), c=0x02, timeout_s=1.0)


def test_plc_stop_holds_text_blocks_until_run() -> None:
    plc, _ = make()
    plc.stop()
    tb = plc.start_exchange(m=m_of(3), c=0x0F, recv_bytes=27)
    plc.advance(0.1)
    assert not tb.done
    plc.start()
    plc.advance(0.03)
    assert tb.done


def test_cold_restart_reinitialises_the_modules() -> None:
    plc, mod = make()
    plc.write("OW3,0,C", 1)
    plc.advance(0.02)
    assert plc.read("IW3,0,C") == 1
    plc.cold_restart()
    plc.advance(0.02)
    assert plc.read("IW3,0,9") == 1 and plc.read("OW3,0,C") == 0
    assert mod.power_ups == 2


def test_bad_plc_arguments() -> None:
    with pytest.raises(ConfigError, match="unknown PLC model 'TSX 99'"):
        Plc(model="TSX 99")
    with pytest.raises(ConfigError, match="scan_ms"):
        Plc(scan_ms=0)
    with pytest.raises(ConfigError, match="unknown module type 'TSX XYZ'"):
        Plc().insert("TSX XYZ", rack=0, slot=1)
    plc = Plc()
    plc.insert(DOUBLE, rack=0, slot=1)
    with pytest.raises(ConfigError, match="already taken"):
        plc.insert(DOUBLE, rack=0, slot=1)
    with pytest.raises(ConfigError, match="W4096"):
        plc.read("W4096")
    with pytest.raises(ConfigError, match="no module in rack 0 slot 2"):
        plc.read("IW2,0")


def test_short_power_break_frees_the_channel_of_a_held_exchange() -> None:
    # manual-notes F-9: any break ends the exchange with TXTi,S = 3; the module must
    # forget it too, else every later exchange on the channel gets TXTi,S = 5
    plc, mod = make()
    tb = plc.start_exchange(m=m_of(3), c=0x02)
    plc.advance(0.02)
    plc.power_break(0.005)
    assert tb.result is not None and tb.result.s == 3 and mod.power_ups == 1
    assert mod.pending_exchange(0x63) is None
    r = plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27, txt=1)
    assert not r.e and r.v == 0x3F


def test_no_master_task_during_a_power_break() -> None:
    plc, _ = make()
    cycles = plc.cycles
    plc.power_break(0.5)
    assert plc.cycles == cycles
    plc.advance(0.01)
    assert plc.cycles == cycles + 1
    with pytest.raises(ConfigError, match="power break of -1"):
        plc.power_break(-1)


def test_error_4_for_a_module_pulled_out_during_the_exchange() -> None:
    # F-6: 4 = module fault ("module absent", AEM 4.4-1), 3 is the PLC's power break
    plc, mod = make()
    tb = plc.start_exchange(m=m_of(3), c=0x02)
    plc.advance(0.02)
    plc.remove(0, 3)
    assert tb.result is not None and (tb.result.e, tb.result.s) == (True, 4)
    plc.reinsert(0, 3)
    assert plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27).v == 0x3F


def test_cold_restart_ends_a_held_exchange_and_frees_the_channel() -> None:
    plc, mod = make()
    tb = plc.start_exchange(m=m_of(3), c=0x02)
    plc.advance(0.02)
    plc.cold_restart()
    assert tb.result is not None and tb.result.s == 3
    assert plc.exchange(m=m_of(3), c=0x0F, recv_bytes=27).v == 0x3F


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"indirect": 5000}, "table W5000 out of range"),
        ({"indirect": -1}, "table W-1 out of range"),
        ({"recv_bytes": -1}, "reception capacity -1 not allowed"),
        ({"txt": -1}, "TXT-1: a Text Block number cannot be negative"),
    ],
)
def test_bad_text_block_arguments_are_config_errors(kw: dict[str, int], message: str) -> None:
    plc, _ = make()
    with pytest.raises(ConfigError, match=message):
        plc.start_exchange(m=m_of(3), c=0x01, length=2, **kw)


# --- the public API in seconds (issue 9 item 6) ------------------------------------


def test_now_s_and_advance_to_absolute_simulated_time() -> None:
    plc = Plc(scan_ms=10)
    assert plc.now_s == 0.0
    plc.advance_to(2.5)
    assert plc.now_s == 2.5 and plc.now_us == 2_500_000 and plc.now == 2_500_000
    plc.advance_to(2.5)  # already there: nothing happens
    assert plc.cycles == 250
    with pytest.raises(ConfigError, match=r"cannot advance to t = 1.0 s.*never goes back"):
        plc.advance_to(1.0)
    with pytest.raises(ConfigError, match="cannot advance to t = inf"):
        plc.advance_to(float("inf"))
    with pytest.raises(ConfigError, match="cannot advance by 1e\\+308 s"):
        plc.advance(1e308)
    assert plc.now_s == 2.5


def test_read_signed_words() -> None:
    plc, _ = make()
    plc.write("OW3,2", 0xFF38)
    plc.write("W7", 0x8000)
    assert plc.read("OW3,2") == 0xFF38 and plc.read_signed("OW3,2") == -200
    assert plc.read_signed("W7") == -32768 and plc.read_signed("IW3,5") == 0
    plc.write("W7", 0x7FFF)
    assert plc.read_signed("W7") == 32767
    for name in ("I3,0", "IW3,0,3", "I3,S"):
        with pytest.raises(ConfigError, match="is not a word: read_signed takes"):
            plc.read_signed(name)


def test_start_exchange_handle_done_result_ended_at_in_seconds() -> None:
    plc, _ = make()
    tb = plc.start_exchange(m=m_of(3), c=0x0F, recv_bytes=27)
    assert not tb.done and tb.result is None and tb.ended_at is None
    plc.advance(0.05)
    assert tb.done and tb.result is not None and tb.result.v == 0x3F
    assert tb.ended_at == tb.result.ended_at == tb.result.ended_at_us / 1e6
    assert 2.1 < tb.ended_at <= plc.now_s and tb.ended_at * 1e6 % SCAN == 0


def test_signed_words_on_exchange_results() -> None:
    plc, _ = make()
    plc.write("W200", 0xFF38)
    plc.write("W201", 0x0064)
    r = plc.exchange(m=m_of(3), c=0x01, table=200, length=4, recv_bytes=4)
    assert r.words == [0xFF38, 0x0064] and r.signed_words == [-200, 100]


def test_power_break_leaves_a_fresh_input_image_and_keeps_outputs_and_words() -> None:
    # docs/objects.md: after power_break() the input image is read from the modules at
    # power return (here: the self-test of a long break), outputs and W words kept
    plc, mod = make()
    plc.write("OW3,0,C", 1)
    plc.write("W9", 1234)
    plc.advance(0.02)
    assert plc.read("IW3,0,3") == 1 and plc.read("IW3,0,9") == 0
    plc.power_break(0.5)
    assert plc.read("IW3,0,9") == 1 and plc.read("IW3,0,3") == 0  # fresh: in self-test
    assert plc.read("OW3,0,C") == 1 and plc.read("W9") == 1234
    plc.power_break(0.005)  # short: no restart, the image still fresh
    assert plc.read("IW3,0,9") == 1


def test_insert_and_module_return_the_module_and_module_as_checks_the_kind() -> None:
    plc, mod = make()
    assert plc.module(0, 3) is mod and plc.module_as(Double, 0, 3) is mod
    from fieldtwin.tsx.aem811 import Aem811

    with pytest.raises(ConfigError, match="rack 0 slot 3 holds a TEST DOUBLE, not a TSX AEM 811"):
        plc.module_as(Aem811, 0, 3)
    with pytest.raises(ConfigError, match="no module in rack 0 slot 4"):
        plc.module(0, 4)


def test_dem_6_2_2_at_most_32_time_stamping_modules_in_one_plc() -> None:
    # DEM 6.2-2 note: "limited to 32 in a single PLC configuration", 2412 and 2413 alike
    plc = Plc(model="TSX 87", scan_ms=10)
    places = [(rack, slot) for rack in range(8) for slot in range(8)]
    for i, (rack, slot) in enumerate(places[:32]):
        plc.insert("TSX DEM 2412" if i % 2 else "TSX DEM 2413", rack=rack, slot=slot)
    with pytest.raises(ConfigError, match=r"at most 32 time-stamping modules \(32 already"):
        plc.insert("TSX DEM 2412", rack=4, slot=0)
    plc.insert("TSX AEM 811", rack=4, slot=0)  # other kinds are not counted
    assert len(plc.modules) == 33


def test_dem_6_2_2_limit_in_a_plant_file(tmp_path: Path) -> None:
    from fieldtwin.plant import load_plant

    places = [(rack, slot) for rack in range(8) for slot in range(8)][:33]
    modules = "".join(
        f'[[module]]\ntype = "TSX DEM 2412"\nrack = {rack}\nslot = {slot}\n\n'
        for rack, slot in places
    )
    plant = tmp_path / "dems.toml"
    plant.write_text('[plc]\nmodel = "TSX 87"\n\n' + modules)
    with pytest.raises(ConfigError, match=r"module\[32\].*at most 32 time-stamping modules"):
        load_plant(plant)


def test_text_blocks_are_txt0_to_txt63() -> None:
    # issue 10 item 21: `txt 9999` had no range check; AEM 3.5-1 "N/MAX : 4 /64"
    plc = Plc(model="TSX 87", scan_ms=10)
    assert plc.text_block(63).index == 63
    with pytest.raises(ConfigError, match=r"TXT64: no such Text Block \(allowed TXT0..TXT63"):
        plc.text_block(64)
    with pytest.raises(ConfigError, match="TXT-1"):
        plc.start_exchange(m=0x0563, c=0x0F, txt=-1)
