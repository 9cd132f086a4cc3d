"""The Device face over every kind: registry, plant schema, build context, binder."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.clock import SimClock
from fieldtwin.devices import registry
from fieldtwin.devices.face import Family, ModuleAddress, TesAddress
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.errors import ConfigError
from fieldtwin.plant import _parse, build_plant, load_plant
from fieldtwin.runtime.binder import bind
from fieldtwin.runtime.runner import Runner

TWO_LINES = """
[[tes]]
model = "TES 32EST"
slave = 1
endpoint = "tcp://127.0.0.1:0"
[[tes]]
model = "TES 8EA"
slave = 1
endpoint = "pty"
"""


def _plant(text: str):  # type: ignore[no-untyped-def]
    return build_plant(_parse(text, "p.toml", Path(".")), speed=None)


def test_one_registry_holds_modules_and_tes() -> None:
    modules = {k.name for k in registry.kinds(Family.MODULE)}
    tes = [k.name for k in registry.kinds(Family.TES)]
    assert {"TSX AEM 811", "TSX DEM 2412", "TSX DEM 2413", "TSX SCM 2111"} <= modules
    assert tes[0] == "TES 16EST" and "TES 8EA" in tes and len(tes) == 10
    assert registry.kind_named("8ea", Family.TES).name == "TES 8EA"
    with pytest.raises(ConfigError, match=r"unknown module type 'TSX FOO' \(allowed: TSX AEM"):
        registry.kind_named("TSX FOO", Family.MODULE)


def test_every_device_shows_the_same_face() -> None:
    plant = load_plant(None, speed=None)
    try:
        assert plant.plc is not None
        plant.plc.advance(12.0)
        by_kind = {d.kind: d for d in plant.devices}
        aem, scm, tes = by_kind["TSX AEM 811"], by_kind["TSX SCM 2111"], by_kind["TES 8EA"]
        assert aem.address == ModuleAddress(0, 5)
        assert tes.address == TesAddress("tcp://127.0.0.1:5020", 2)
        assert str(tes.address) == "tcp://127.0.0.1:5020 2"
        assert aem.status().mode == "Run" and aem.status().led_map == {
            "OK": "on",
            "ERR": "off",
            "F": "off",
        }
        assert scm.status().mode is None  # SCM 1.2: no Run/Stop of its own
        assert [p.name for p in scm.status().ports] == ["channel 0", "channel 1"]
        assert tes.status().led_map["Pwr"] == "on" and tes.status().mode is None
        assert set(aem.inputs()) == {str(i) for i in range(8)}
        assert "a0" in tes.inputs() and "0.CTS" in scm.inputs()
        tes.input("a0").set(5.0)
        plant.plc.advance(1.0)
        assert tes.objects().peek("H'003'") == 512  # 5 V, as tes/model.py's example
        tes.fault("power_off").set()
        assert tes.status().state == "off"
        tes.fault("power_off").clear()
        assert tes.status().state == "on"
        with pytest.raises(ConfigError, match=r"TSX AEM 811 5: no input 'x' \(allowed: 0..7\)"):
            aem.input("x")
        with pytest.raises(ConfigError, match=r"unknown fault 'smoke' for TSX AEM 811 5"):
            aem.fault("smoke")
    finally:
        plant.close()


def test_two_tes_with_one_slave_number_on_two_endpoints_are_told_apart() -> None:
    plant = _plant(TWO_LINES)
    assert plant.tes_device(1, "pty").kind == "TES 8EA"
    assert plant.tes_device(1, "tcp://127.0.0.1:0").kind == "TES 32EST"
    with pytest.raises(ConfigError, match="slave number 1 answers on 2 endpoints: name the"):
        plant.tes_device(1)
    with pytest.raises(ConfigError, match="no TES with slave number 3"):
        plant.tes_device(3)


def test_endpoints_open_only_when_bound() -> None:
    text = (
        '[[module]]\ntype = "TSX SCM 2111"\nslot = 7\n'
        'channels = [{ channel = 0, endpoint = "pty" }]\n' + TWO_LINES
    )
    runner = Runner(SimClock(), None)
    plant = build_plant(_parse(text, "p.toml", Path(".")), runner=runner, speed=None)
    assert plant.plc is not None
    scm = plant.plc.module(0, 7)
    assert scm.ports[0] is None  # nothing opened while the plant was built
    binding = bind(plant.devices, runner)
    try:
        assert scm.ports[0] is not None and scm.ports[0].path.startswith("/dev/")
        assert any(
            line.startswith("listening: modbus-tcp tcp://127.0.0.1:") for line in binding.lines
        )
        assert any("TSX SCM 2111 slot 7 channel 0" in line for line in binding.lines)
    finally:
        binding.close()
    assert scm.ports[0] is None


def test_the_plant_configuration_is_sent_after_the_first_self_test_only() -> None:
    # docs/plant.md: one rule for every kind (the DEM's used to be sent after every
    # self-test, the AEM's once); a power break loses it as on the modules (2.5-3)
    plant = _plant(
        '[plc]\noutputs = { "OW5,0,C" = 1 }\n'
        '[[module]]\ntype = "TSX AEM 811"\nslot = 5\nconfig = { period = 30 }\n'
        '[[module]]\ntype = "TSX DEM 2412"\nslot = 4\n'
        "config = [\"H'0010'\", 10, 0, 0, 0, 0, 30, 10, 1]\n"
    )
    plc = plant.plc
    assert plc is not None
    plc.advance(11.0)
    assert plc.read("IW5,2,D") == 0  # IW5,2,D: the default configuration is gone
    assert not plc.module(0, 4).default_config
    plc.power_break(1.0)
    plc.advance(11.0)
    assert plc.read("IW5,2,D") == 1  # lost with the power, not sent again
    assert plc.module(0, 4).default_config


def test_unknown_keys_name_the_kind_and_the_field() -> None:
    with pytest.raises(ConfigError) as info:
        _plant('[[module]]\ntype = "TSX SCM 2111"\nslot = 7\nwires = 1\n')
    assert str(info.value) == (
        "p.toml: module[0]: unknown key(s) wires (module[0].wires is not a key of TSX SCM 2111;"
        " allowed: type, rack, slot, code, adaptors, faults, channels)"
    )


def test_a_sync_partner_is_found_through_the_plc() -> None:
    with pytest.raises(ConfigError, match=r"module\[0\]\.sync\.from_slot: no module in rack 0"):
        _plant('[[module]]\ntype = "TSX DEM 2412"\nslot = 5\nsync = { from_slot = 3 }\n')
    with pytest.raises(ConfigError, match="holds a TSX AEM 811, not a time-stamping module"):
        _plant(
            '[[module]]\ntype = "TSX DEM 2412"\nslot = 5\nsync = { from_slot = 3 }\n'
            '[[module]]\ntype = "TSX AEM 811"\nslot = 3\n'
        )


IDENTITY = {Family.MODULE: {"slot": 3}, Family.TES: {"endpoint": "pty", "slave": 9}}


@pytest.mark.parametrize("kind", registry.kinds(), ids=lambda k: k.name)
def test_every_kind_refuses_an_unknown_key_the_same_way(kind: DeviceKind) -> None:
    key = "type" if kind.family is Family.MODULE else "model"
    table = {key: kind.name, **IDENTITY[kind.family], "colour": "red"}
    section = "module" if kind.family is Family.MODULE else "tes"
    text = "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in table.items())
    with pytest.raises(ConfigError) as info:
        _plant(f"[[{section}]]\n{text}\n")
    assert str(info.value).startswith(
        f"p.toml: {section}[0]: unknown key(s) colour ({section}[0].colour is not a key of"
        f" {kind.name}; allowed: {key}, "
    )
