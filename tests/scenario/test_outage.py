"""Outages that last (issue 22 item 4): a TES's power-cycle with a duration, in process
(console, control API object) and seen by a pymodbus poller of a real `fieldtwin run`."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ConnectionException, ModbusIOException

from fieldtwin.client import Client, ControlError
from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.plant import Plant, load_plant
from fieldtwin.plant.outage import MAX_OUTAGE_S
from tests.control.plantproc import Running, default_plant_copy, fieldtwin_run

STATUS = 0x000  # TES status word: bit 0 = powered on again (restart)
FILTER_0 = 0x00A  # TES 32EST: MP word, EEPROM value 1


@pytest.fixture()
def plant() -> Plant:
    return load_plant(None)


def test_an_outage_lasts_its_seconds_with_leds_off_then_ram_reset_and_eeprom_reload(
    plant: Plant,
) -> None:
    console = Console(plant)
    console.execute("advance 1")
    tes1 = plant.tes_device(1)
    tes1.objects().write(str(FILTER_0), 40)  # RAM only: the EEPROM keeps 1
    tes1.objects().write(str(STATUS), 0)  # the restart bit acknowledged
    assert console.execute("tes 1 power-cycle 2") == ["tes 1 power off until t = 3.000 s"]
    assert dict(tes1.status().leds) == {"Pwr": "off", "Run": "off", "Prm": "off", "Wdg": "off"}
    assert tes1.status().state == "off"
    console.execute("advance 1.999")
    assert dict(tes1.status().leds)["Pwr"] == "off"
    console.execute("advance 0.001")
    assert dict(tes1.status().leds)["Pwr"] == "on"
    assert tes1.objects().peek(str(FILTER_0)) == 1  # reloaded from the EEPROM (TES §1)
    assert tes1.objects().peek(str(STATUS)) & 0x1 == 0x1  # the restart bit


def test_an_outage_is_bounded_and_one_at_a_time(plant: Plant) -> None:
    console = Console(plant)
    with pytest.raises(ConfigError, match=r"seconds: 3601\.0 not allowed .*0 to 3600"):
        console.execute("tes 1 power-cycle 3601")
    console.execute("tes 1 power-cycle 5")
    with pytest.raises(ConfigError, match=r"tes 1 is off until t = 5\.000 s"):
        console.execute("tes 1 power-cycle")
    console.execute("advance 5")
    assert console.execute("tes 1 power-cycle") == ["tes 1 power cycled"]  # at once, as before
    assert MAX_OUTAGE_S == 3600


def _status(master: ModbusTcpClient, slave: int) -> int | None:
    try:
        reply = master.read_holding_registers(STATUS, count=1, device_id=slave)
    except (ModbusIOException, ConnectionException):
        return None
    return None if reply.isError() else int(reply.registers[0])


@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    with fieldtwin_run(default_plant_copy(tmp_path_factory.mktemp("outage"))) as run:
        yield run


def test_a_poller_sees_a_2_s_power_cycle_as_2_s_of_timeouts_then_the_restart_bit(
    running: Running,
) -> None:
    period_s, outage_s = 0.25, 2.0
    master = ModbusTcpClient("127.0.0.1", port=running.modbus_port, timeout=0.2, retries=0)
    assert master.connect()  # type: ignore[no-untyped-call]
    api = Client(running.url)
    try:
        assert master.write_register(STATUS, 0, device_id=2).isError() is False  # acknowledged
        assert _status(master, 2) == 0
        answer = api.power_cycle("tes2", outage_s)
        assert answer["power"] == "off" and answer["back_at_s"] > 0
        with pytest.raises(ControlError) as busy:
            api.power_cycle("tes2", 1)
        assert busy.value.status == 409 and "is off until" in str(busy.value)
        polls: list[tuple[float, int | None]] = []
        start = time.monotonic()
        while time.monotonic() - start < outage_s + 3:  # bounded: the outage and some
            began = time.monotonic()
            polls.append((began, _status(master, 2)))
            if polls[-1][1] is not None and len(polls) > 1 and polls[-2][1] is None:
                break
            time.sleep(max(0.0, period_s - (time.monotonic() - began)))
        silent = [t for t, value in polls if value is None]
        assert silent, f"no timeout seen: {polls}"
        back_t, back_value = polls[-1]
        assert back_value is not None, f"never answered again: {polls}"
        seen = back_t - silent[0]
        # ± one poll period, and the wall's jitter on a loaded machine
        jitter_s = 0.25
        assert outage_s - period_s - jitter_s <= seen <= outage_s + period_s + jitter_s, polls
        assert back_value & 0x1 == 0x1  # powered on again: the restart bit (TES §1)
    finally:
        master.close()  # type: ignore[no-untyped-call]
        api.close()


def test_the_api_power_cycle_without_a_body_is_instantaneous_as_before(running: Running) -> None:
    with Client(running.url) as api:
        assert api.power_cycle("tes1") == {"device": "tes1", "power": "cycled"}
        with pytest.raises(ControlError) as bad:
            api.request("POST", "/devices/tes1/power-cycle", {"seconds": 4000})
        assert bad.value.status in (400, 422)
        with pytest.raises(ControlError) as module:
            api.power_cycle("5", 2)
        assert module.value.status == 400 and "power break" in str(module.value)
