"""The AEM 811 through the PLC: requests, thresholds, faults, self-test, codes, power."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.devices.aem811.plantkeys import read_plant_table
from fieldtwin.devices.aem811.status import lines as status_lines
from fieldtwin.devices.aem811.values import set_value
from fieldtwin.errors import ConfigError
from fieldtwin.facade import fault_names, inject_fault
from fieldtwin.tsx.aem811.faults import describe
from tests.tsx.aem811.helpers import CHN, SYS, at, configure, make, ready, run, until, words


def test_7_1_1_initial_self_test_and_default_configuration() -> None:
    plc, mod = make()
    plc.advance(9.9)
    assert plc.read("IW5,0,9") == 1 and plc.read("IW5,0,3") == 0
    assert mod.leds == {"OK": "on", "ERR": "on", "F": "off"}
    plc.advance(0.2)
    assert plc.read("IW5,0,9") == 0 and plc.read("IW5,0,3") == 1
    assert plc.read("IW5,2,D") == 1 and plc.read("IW5,0,B") == 0  # AEM 3.3
    r = plc.exchange(m=SYS, c=0x41, recv_bytes=68)
    assert r.v == 0x71 and r.words[:4] == [0x00A0, 10, 0x00C0, 0x00A0]


def test_3_4_2_configuration_accepted_only_in_stop() -> None:
    plc, mod = ready()
    run(plc, mod)
    r = configure(plc, [0x00A0, 30])
    assert (r.v, r.e) == (0xFD, False)  # AMB-AEM-23
    assert plc.read("IW5,0,B") == 0 and mod.config.period == 10
    plc.write("OW5,0,C", 0)
    plc.advance(0.02)
    r = configure(plc, [0x00A0, 30, 0x00C2, 0x00C0, 8800, 880])
    assert r.v == 0xFE
    plc.advance(0.02)
    assert plc.read("IW5,2,D") == 0 and plc.read("IW5,0,B") == 0
    r = plc.exchange(m=SYS, c=0x41, send=[0x00C2], recv_bytes=12)
    assert (r.v, r.words) == (0x71, [0x00A0, 30, 0x00C2, 0x00C0, 8800, 880])


def test_3_4_3_refused_configuration_keeps_the_previous_one() -> None:
    plc, mod = ready()
    assert configure(plc, [0x00A0, 30, 0x00C1, 0x40B0]).v == 0xFE
    r = plc.exchange(m=SYS, c=0x40, send=words([0x00C0, 0x80A1]))  # test on 4/20 mA
    assert r.v == 0xFD
    plc.write("OW5,0,C", 1)
    plc.advance(0.05)
    assert plc.read("IW5,0,B") == 1 and plc.read("IW5,0,C") == 0  # awaits, stopped
    assert mod.config.period == 30 and mod.config.channels[1].mode_word == 0x40B0
    assert "current" in status_lines(mod)["last refusal"]
    plc.write("OW5,0,C", 0)
    assert configure(plc, [0x00A0, 40]).v == 0xFE
    plc.write("OW5,0,C", 1)
    plc.advance(0.05)
    assert plc.read("IW5,0,B") == 0 and plc.read("IW5,0,C") == 1


def test_3_4_3_length_errors() -> None:
    plc, mod = ready()
    assert plc.exchange(m=SYS, c=0x40, send_bytes=bytes(2)).v == 0xFD
    assert plc.exchange(m=SYS, c=0x40, send_bytes=bytes(70)).v == 0xFD
    plc.advance(0.02)
    assert plc.read("IW5,0,B") == 1 and plc.read("IW5,2,D") == 1


def test_2_5_3_power_break_loses_configuration_and_thresholds() -> None:
    plc, mod = ready()
    configure(plc, [0x00A0, 30])
    tb = plc.start_exchange(m=CHN, c=2, send=[5] * 8)  # held: module stopped
    run(plc, mod)
    plc.advance(0.5)
    assert tb.done and mod.thresholds.values[0] == [5] * 8
    plc.power_break(1.0)
    plc.advance(10.1)
    assert plc.read("IW5,2,D") == 1 and mod.config.period == 10
    assert plc.exchange(m=CHN, c=3, recv_bytes=16).words == [0] * 8


def test_4_3_1_threshold_write_held_until_run() -> None:
    plc, mod = ready()
    tb = plc.start_exchange(m=CHN, c=4, send=words([-5, 1, 2, 3, 4, 5, 6, 7]))
    plc.advance(3)
    assert not tb.done
    t = run(plc, mod)
    until(plc, at(t, 100))  # acknowledged once compared (first acquisition)
    plc.advance(0.02)
    assert tb.done and tb.result is not None and tb.result.v == 0xFE
    r = plc.exchange(m=CHN, c=5, recv_bytes=16)
    assert (r.v, r.s) == (0x85, 16)
    assert r.words == words([-5, 1, 2, 3, 4, 5, 6, 7])
    assert plc.exchange(m=CHN, c=3, recv_bytes=16).v == 0x83
    assert plc.exchange(m=CHN, c=2, send=[1, 2]).v == 0xFD  # not 16 bytes


def test_2_3_5_threshold_bits_with_hysteresis() -> None:
    plc, mod = ready(quantize=False)
    configure(plc, [0x00C0, 0x20C0, 1000, 0])  # 0/10 V user 0..1000: h = 6
    run(plc, mod)
    plc.exchange(m=CHN, c=2, send=[500] + [0] * 7)
    plc.exchange(m=CHN, c=4, send=[700] + [0] * 7)

    def after(volts: float) -> tuple[int, int]:
        mod.set_input(0, volts=volts)
        plc.advance(1.1)  # a full cycle
        return plc.read("I5,0"), plc.read("I5,8")

    assert after(5.02) == (0, 0)  # 502 < 503
    assert after(5.03) == (1, 0)  # >= T + h/2
    assert after(4.98) == (1, 0)  # inside the band
    assert after(4.97) == (0, 0)  # <= T - h/2
    assert after(7.5) == (1, 1)
    plc.write("OW5,1,0", 1)  # inhibited: forced to 0
    plc.advance(0.05)
    assert (plc.read("I5,0"), plc.read("I5,8")) == (0, 0)
    assert plc.read("IW5,1,0") == 1


def test_4_3_3_new_thresholds_after_a_full_cycle() -> None:
    plc, mod = ready(quantize=False)
    for ch in range(8):
        mod.set_input(ch, volts=5.0)
    t = run(plc, mod)
    until(plc, at(t, 1000))
    assert plc.read("I5,7") == 1  # 5000 >= 0 + 50
    plc.write("OW5,0,C", 1)
    r = plc.exchange(m=CHN, c=2, send=[6000] * 8)
    assert r.v == 0xFE
    plc.advance(0.1)
    assert 0 < mod.thresholds.bits & 0xFF < 0xFF  # some channels compared already
    plc.advance(1.0)
    assert mod.thresholds.bits & 0xFF == 0


def test_4_4_1_continuity_fault_and_fault_string() -> None:
    plc, mod = ready()
    configure(plc, [0x00A0, 24, 0x00C3, 0x20A1])
    run(plc, mod)
    mod.set_input(3, open_circuit=True)
    plc.advance(0.45)
    assert plc.read("IW5,6") == 11000 and plc.read("IW5,2,3") == 0  # AEM 2.3-4: EHL
    assert plc.read("IW5,1,B") == 1 and plc.read("IW5,0,7") == 1 and plc.read("IW5,0,4") == 1
    assert mod.leds["ERR"] == "on" and plc.read("I5,S") == 0 and plc.read("IW5,0,C") == 1
    r = plc.exchange(m=SYS, c=0x47, recv_bytes=10)
    assert (r.v, r.s) == (0x77, 8)  # AMB-AEM-05: 8 bytes
    assert describe(r.data) == ["channel 3 continuity"]
    mod.set_input(3, volts=5.0)
    plc.advance(2.5)
    assert plc.read("IW5,1,B") == 0 and plc.read("IW5,0,7") == 0  # read while present


def test_accelerated_mode_does_not_run_the_continuity_test() -> None:
    plc, mod = ready()
    configure(plc, [0x00A0, 24, 0x00C3, 0x20A1])
    plc.write("OW5,1", 0x1F7)
    run(plc, mod)
    inject_fault(mod, "open_3", True)
    plc.advance(1)
    assert plc.read("IW5,6") == 11000 and plc.read("IW5,1,B") == 0


def test_4_4_1_fault_2_not_reported_until_fault_1_is_gone() -> None:
    plc, mod = ready()
    configure(plc, [0x00C0, 0x80A0, 0x00C1, 0x80A0])  # 4/20 mA: a cut reads under range
    run(plc, mod)
    for ch in (0, 1):
        mod.set_input(ch, milliamps=12)
    plc.advance(1.1)
    inject_fault(mod, "open_0", True)  # fault 1
    plc.advance(1.1)
    assert plc.read("IW5,0,7") == 1
    first = plc.exchange(m=SYS, c=0x47, recv_bytes=8)
    assert describe(first.data) == ["channel 0 ELL exceeded"]
    inject_fault(mod, "open_1", True)  # fault 2: no new edge on IWxy,0,7
    plc.advance(1.1)
    inject_fault(mod, "open_0", False)
    plc.advance(1.1)
    assert plc.read("IW5,0,7") == 1  # fault 2 memorised, still unread
    second = plc.exchange(m=SYS, c=0x47, recv_bytes=8)
    assert describe(second.data) == ["channel 1 ELL exceeded"]
    inject_fault(mod, "open_1", False)
    plc.advance(1.1)
    assert plc.read("IW5,0,7") == 0 and plc.read("IW5,0,4") == 0


@pytest.mark.parametrize(("name", "bit"), [("terminal_block", 16), ("converter", 17)])
def test_7_1_2_module_faults_stop_the_module(name: str, bit: int) -> None:
    plc, mod = ready()
    run(plc, mod)
    inject_fault(mod, name, True)
    plc.advance(0.05)
    assert plc.read("IW5,0,C") == 0 and plc.read("I5,S") == 1 and mod.leds["OK"] == "off"
    assert plc.read("IW5,0,6") == 1 and plc.read("IW5,0,A") == int(name == "terminal_block")
    ops = sum(mod.relay_operations)
    plc.advance(2)
    assert sum(mod.relay_operations) == ops  # stopped: no acquisition
    inject_fault(mod, name, False)
    plc.advance(0.05)
    assert plc.read("IW5,0,C") == 1 and plc.read("I5,S") == 0 and plc.read("IW5,0,A") == 0
    assert plc.read("IW5,0,6") == 1  # memorised
    r = plc.exchange(m=SYS, c=0x47, recv_bytes=8)
    assert r.data[bit // 8] >> (bit % 8) & 1
    plc.advance(0.02)
    assert plc.read("IW5,0,6") == 0


def test_7_1_1_relay_fault_found_by_the_next_self_test() -> None:
    plc, mod = ready()
    inject_fault(mod, "relay", True)
    plc.advance(0.05)
    assert plc.read("IW5,0,6") == 0
    plc.power_break(1.0)
    plc.advance(10.1)
    assert plc.read("IW5,0,6") == 1 and plc.read("I5,S") == 1
    assert describe(plc.exchange(m=SYS, c=0x47, recv_bytes=8).data) == ["input relays"]


def test_blocking_fault() -> None:
    plc, mod = ready()
    inject_fault(mod, "processor", True)
    plc.advance(0.05)
    assert plc.read("IW5,0,8") == 1 and mod.leds == {"OK": "off", "ERR": "off", "F": "on"}
    r = plc.exchange(m=SYS, c=0x0F, recv_bytes=27)
    assert r.e and r.s == 4


@pytest.mark.parametrize(
    ("model", "code", "fault"),
    [
        ("TSX 87", 648, 0),
        ("TSX 87", 62, 1),
        ("TSX 47-20", 62, 0),
        ("TSX 47-20", 648, 1),
        ("TSX 67", 649, 1),
    ],
)
def test_6_1_3_declared_codes(model: str, code: int, fault: int) -> None:
    plc, mod = make(model, code=code)
    plc.advance(10.1)
    slot = mod.slot
    assert plc.read(f"I{slot},S") == fault


def test_common_requests() -> None:
    plc, mod = ready()
    r = plc.exchange(m=SYS, c=0x0F, recv_bytes=27)
    assert r.v == 0x3F and r.data.startswith(b"TSX AEM 811")
    assert plc.exchange(m=SYS, c=0x49, send_bytes=b"TANKS").v == 0xFE
    assert plc.exchange(m=SYS, c=0x4A, recv_bytes=20).data.rstrip() == b"TANKS"
    assert plc.exchange(m=SYS, c=0x33, recv_bytes=20).v == 0xFD
    assert plc.exchange(m=0x0501, c=1, recv_bytes=16).v == 0xFD


def test_relay_operations_in_status() -> None:
    plc, mod = ready()
    run(plc, mod)
    plc.advance(3.05)
    status = status_lines(mod)
    assert status["relay operations"].startswith(f"{sum(mod.relay_operations)} (")
    assert sum(mod.relay_operations) >= 24
    assert "channel 0" in status and status["configuration"] == "default"


def test_console_inputs_and_faults() -> None:
    plc, mod = ready(quantize=False)
    configure(plc, [0x00C1, 0x80A0])
    run(plc, mod)
    set_value(mod, 0, "2.5V")
    set_value(mod, 1, "12mA")
    set_value(mod, 2, "-750mV")
    set_value(mod, 3, "open")
    plc.advance(1.1)
    assert mod.values[:4] == [2500, 12000, -750, 11000]
    with pytest.raises(ConfigError, match="allowed"):
        set_value(mod, 0, "2.5 volts")
    with pytest.raises(ConfigError, match=r"0\.\.7"):
        mod.set_input(8, volts=1)
    with pytest.raises(ConfigError, match="exactly one"):
        mod.set_input(0, volts=1, milliamps=2)
    assert "open_7" in fault_names(mod) and "terminal_block" in fault_names(mod)
    with pytest.raises(ConfigError, match="unknown fault"):
        inject_fault(mod, "smoke", True)


def test_signal_units() -> None:
    from fieldtwin.signals import Constant

    plc, mod = ready(quantize=False)
    configure(plc, [0x00C0, 0x80A0])
    run(plc, mod)
    mod.set_signal(0, Constant(12.0))  # auto: mA on a current range
    mod.set_signal(1, Constant(1.2), unit="V")
    mod.set_signal(2, Constant(12.0), unit="mA")  # 1.2 V across 100 ohm
    plc.advance(1.1)
    assert mod.values[:3] == [12000, 1200, 1200]
    with pytest.raises(ConfigError, match="unit"):
        mod.set_signal(0, Constant(1.0), unit="A")


def test_plant_keys(tmp_path: Path) -> None:
    plc, mod = make(quantize=False)
    read_plant_table(
        mod,
        {
            "config": {
                "period": 30,
                "channels": [
                    {"channel": 0, "range": "4/20mA", "scaling": "user", "high": 10000, "low": 0},
                    {"channel": 4, "mode": "H'21C1'", "high": 20000, "low": 0},
                ],
            },
            "threshold0": [1000] * 8,
            "inputs": [
                {"channel": 0, "milliamps": 12.0},
                {"channel": 4, "volts": {"kind": "ramp", "start": 0, "end": 10, "duration_s": 20}},
            ],
            "faults": ["open_7"],
        },
        "plant.toml: module[0]",
        tmp_path,
    )
    plc.advance(10.1)
    assert plc.read("IW5,2,D") == 0 and mod.config.period == 30
    assert mod.thresholds.values[0] == [1000] * 8
    run(plc, mod)
    plc.advance(3)
    assert mod.values[0] == 5000 and plc.read("I5,0") == 1 and mod.values[4] > 0
    with pytest.raises(ConfigError, match=r"module\[0\].config: the module would refuse"):
        read_plant_table(
            mod,
            {"config": {"channels": [{"channel": 1, "mode": "H'20A1'"}]}},
            "module[0]",
            tmp_path,
        )
    with pytest.raises(ConfigError, match="unknown key"):
        read_plant_table(mod, {"colour": 1}, "module[0]", tmp_path)


def test_4_4_3_footnote_other_word_reads_the_whole_configuration() -> None:
    # AEM 4.4-3 (*): with a transmission length defined, a word other than H'XXCi'
    # returns the whole configuration, V = H'71' (it answered H'FD' before)
    plc, mod = ready()
    r = plc.exchange(m=SYS, c=0x41, send=[0x1234], recv_bytes=68)
    assert (r.v, r.e) == (0x71, False) and r.words == mod.config.words()
    r = plc.exchange(m=SYS, c=0x41, send=[0xFFC7], recv_bytes=12)
    assert r.v == 0x71 and r.words[2] == 0x00C7


def test_run_started_at_in_seconds() -> None:
    plc, mod = ready()
    assert mod.run_started_at is None
    started = run(plc, mod)
    assert mod.run_started_at == started / 1e6 and mod.run_started_at_us == started
