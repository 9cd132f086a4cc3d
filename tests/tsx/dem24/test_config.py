"""Configuration (DEM 3.1-3.4): default, write in STOP, checks, read back, codes."""

from __future__ import annotations

import pytest

from fieldtwin.tsx.dem24.config import DEFAULT_CONFIG, Refusal, check_config
from fieldtwin.tsx.plc import Plc
from tests.tsx.dem24.helpers import (
    ASSEMBLY,
    JULY_15_1994,
    M_SYS,
    SLOT,
    configure,
    make,
    read_all,
    send_time,
    synced,
)


def test_3_3_default_configuration_and_read_back() -> None:
    plc, mod = make()
    assert plc.read(f"IW{SLOT},2,D") == 1 and plc.read(f"IW{SLOT},0,B") == 0
    r = plc.exchange(m=M_SYS, c=0x41, recv_bytes=18)
    assert (r.v, r.s) == (0x71, 18)
    assert r.words == [0, 0, 0, 0, 0, 0, 60, 2, 0] == DEFAULT_CONFIG.words()


def test_5_3_3_assembly_line_configuration_is_accepted_and_read_back() -> None:
    plc, mod = make()
    r = configure(plc, ASSEMBLY)
    assert (r.v, r.e) == (0xFE, False)
    assert plc.read(f"IW{SLOT},2,D") == 0 and plc.read(f"IW{SLOT},0,C") == 1
    back = plc.exchange(m=M_SYS, c=0x41, recv_bytes=18)
    assert back.words == ASSEMBLY
    cfg = mod.config
    assert cfg.periodic and cfg.oscillation and not cfg.supply_monitoring and not cfg.maintain
    assert (cfg.filt_ms, cfg.t_syn_s, cfg.drift_ms, cfg.per_min) == (10, 60, 500, 60)


def test_3_4_3_configuration_refused_while_running() -> None:
    plc, mod = make()
    plc.write(f"OW{SLOT},0,C", 1)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,C") == 1
    r = plc.exchange(m=M_SYS, c=0x40, send=ASSEMBLY)
    assert r.v == 0xFD
    plc.advance(0.03)
    assert mod.config == DEFAULT_CONFIG and plc.read(f"IW{SLOT},0,B") == 0  # AMB-DEM-18


@pytest.mark.parametrize(
    ("words", "bits"),
    [
        ([0, 15, 0, 0, 0, 0, 60, 2, 0], {1}),  # FILT
        ([0x4, 0, 5, 0, 5, 2, 60, 2, 0], {2}),  # N-MAX 0 with OSC
        ([0x4, 0, 241, 3, 5, 2, 60, 2, 0], {2}),  # T-MAX 241
        ([0, 0, 0, 0, 0, 0, 20, 2, 0], {3}),  # T-SYN
        ([0, 0, 0, 0, 0, 0, 60, 3, 0], {4}),  # DRIFT
        ([0, 0, 0, 0, 0, 0, 1, 500, 0], {3, 4}),  # 3.2-1 warning: 500 ms with 1 s
        ([0x10, 0, 0, 0, 0, 0, 60, 2, 0], {5}),  # PER 0 with LOG (AMB-DEM-10)
        ([0x10, 0, 0, 0, 0, 0, 60, 2, 241], {5}),
        ([0, 15, 0, 0, 0, 0, 20, 3, 0], {1}),  # "the system stops at the first error"
    ],
)
def test_3_1_3_diagnostic_bits(words: list[int], bits: set[int]) -> None:
    plc, mod = make()
    r = configure(plc, words)
    assert r.v == 0xFD
    iw2 = plc.read(f"IW{SLOT},2")
    assert {b for b in range(1, 6) if iw2 >> b & 1} == bits
    assert plc.read(f"IW{SLOT},0,B") == 1 and plc.read(f"IW{SLOT},0,C") == 0
    assert mod.leds["ERR"] == "on"  # DEM 4.3 ERR: parameter refusal
    fault = plc.exchange(m=M_SYS, c=0x47, recv_bytes=12)
    assert fault.s == 12 and fault.data[4] & 0x08  # bit 35 configuration refused
    assert configure(plc, ASSEMBLY).v == 0xFE
    assert plc.read(f"IW{SLOT},0,B") == 0 and plc.read(f"IW{SLOT},2") & 0x3E == 0
    assert plc.read(f"IW{SLOT},0,C") == 1


def test_undefined_word0_bits_and_wrong_length_are_refused() -> None:
    assert isinstance(check_config([0x0100, 0, 0, 0, 0, 0, 60, 2, 0]), Refusal)
    plc, mod = make()
    plc.write(f"OW{SLOT},0,C", 0)
    plc.advance(0.03)
    r = plc.exchange(m=M_SYS, c=0x40, send=ASSEMBLY[:8])
    assert r.v == 0xFD
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,B") == 1


def test_osc_values_ignored_without_osc() -> None:
    assert check_config([0, 0, 0, 0, 0, 0, 60, 2, 0]) == DEFAULT_CONFIG


def test_3_4_3_refused_configuration_stops_time_stamping() -> None:
    plc, mod = synced()
    plc.write(f"OW{SLOT},0,C", 0)
    plc.advance(0.03)
    plc.exchange(m=M_SYS, c=0x40, send=[0, 15, 0, 0, 0, 0, 60, 2, 0])
    mod.set_input(0, True)
    plc.advance(0.05)
    assert read_all(plc) == [] and plc.read(f"IW{SLOT},2,0") == 1
    assert plc.read(f"IW{SLOT},6,0") == 1  # the input image still follows


@pytest.mark.parametrize(
    ("type_name", "model", "code", "fault"),
    [
        ("TSX DEM 2412", "TSX 87", 777, 0),
        ("TSX DEM 2412", "TSX 87", 778, 1),
        ("TSX DEM 2413", "TSX 67", 778, 0),
        ("TSX DEM 2413", "TSX 47-30", 777, 1),
        ("TSX DEM 2412", "TSX 47-20", 777, 0),  # 6.1 "Program: entered during configuration"
        ("TSX DEM 2413", "TSX 47-20", 778, 0),
    ],
)
def test_6_1_declared_codes(type_name: str, model: str, code: int, fault: int) -> None:
    plc = Plc(model=model, scan_ms=10)
    plc.insert(type_name, rack=0, slot=2, code=code)
    plc.advance(10.1)
    assert plc.read("I2,S") == fault


def test_version_and_application_name_requests() -> None:
    plc, mod = make("TSX DEM 2413")
    r = plc.exchange(m=M_SYS, c=0x0F, recv_bytes=27)
    assert r.v == 0x3F and r.data.startswith(b"TSX DEM 2413")
    assert plc.exchange(m=M_SYS, c=0x49, send_bytes=b"LINE 4").v == 0xFE
    assert plc.exchange(m=M_SYS, c=0x4A, recv_bytes=20).data.startswith(b"LINE 4")
    assert plc.exchange(m=M_SYS, c=0x33, recv_bytes=20).v == 0xFD
    assert send_time(plc, JULY_15_1994).v == 0xFE
