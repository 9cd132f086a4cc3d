"""The control API of a real `fieldtwin run` (subprocess), with a pymodbus master polling."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest
from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ConnectionException, ModbusIOException

from fieldtwin.client import Client, ControlError
from tests.control.plantproc import ROOT, Running, default_plant_copy, fieldtwin_run

WAIT_S = 10.0
DIRECT_0 = 0x005  # TES 32EST: direct inputs [15..00]
FILTER_0 = 0x00A  # TES 32EST: MP word, filter for state 0 (EEPROM value 1 = 5 ms)


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    with fieldtwin_run(default_plant_copy(tmp_path_factory.mktemp("control"))) as running:
        assert running.url.startswith("http://127.0.0.1:")
        assert running.modbus_port > 0
        yield running


@pytest.fixture()
def master(plant: Running) -> Iterator[ModbusTcpClient]:
    client = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=1, retries=0)
    assert client.connect()  # type: ignore[no-untyped-call]
    yield client
    client.close()  # type: ignore[no-untyped-call]


def until(check: Callable[[], bool], what: str, wait_s: float = WAIT_S) -> None:
    deadline = time.monotonic() + wait_s
    while not check():
        assert time.monotonic() < deadline, f"not within {wait_s} s: {what}"
        time.sleep(0.05)


def word(master: ModbusTcpClient, slave: int, address: int) -> int | None:
    try:
        reply = master.read_holding_registers(address, count=1, device_id=slave)
    except (ModbusIOException, ConnectionException):  # no answer, or the connection closed
        return None
    return None if reply.isError() else int(reply.registers[0])


def test_run_prints_the_control_line_and_the_attach_command(plant: Running) -> None:
    assert f"control: {plant.url}" in plant.lines
    assert f"attach: fieldtwin console --attach {plant.url}" in plant.lines


def test_poll_sees_an_input_a_fault_on_one_tes_only_and_a_power_cycle(
    plant: Running, master: ModbusTcpClient
) -> None:
    api = Client(plant.url)
    api.set_input("tes1", "3", False)
    until(lambda: (word(master, 1, DIRECT_0) or 0) & 0x8 == 0, "input 3 off")
    api.set_input("tes1", "3", True)
    until(lambda: (word(master, 1, DIRECT_0) or 0) & 0x8 == 0x8, "input 3 on seen by the poll")

    api.set_fault("tes1", "no_answer")
    try:
        assert word(master, 1, DIRECT_0) is None  # slave 1 is silent
        assert word(master, 2, 0x000) is not None  # slave 2 keeps answering
        assert word(master, 2, 0x000) is not None
    finally:
        api.clear_fault("tes1", "no_answer")
    until(lambda: word(master, 1, DIRECT_0) is not None, "slave 1 answers again")

    assert not master.write_register(0x000, 0, device_id=1).isError()  # RAM: status reset
    assert not master.write_register(FILTER_0, 40, device_id=1).isError()  # MP word on line
    assert word(master, 1, FILTER_0) == 40
    assert api.power_cycle("tes1") == {"device": "tes1", "power": "cycled"}
    assert word(master, 1, FILTER_0) == 1  # reloaded from the EEPROM (TES §1)
    assert (word(master, 1, 0x000) or 0) & 0x01 == 0x01  # bit 0: powered on again
    api.close()


def test_a_text_block_exchange_through_the_api_on_the_aem(plant: Running) -> None:
    with Client(plant.url) as api:
        until(lambda: api.status("5")["state"] == "operational", "AEM self-test over", 20)
        # TXT7: the default plant's program uses TXT0 for its own configuration (AEM 5.1)
        started = api.start_exchange(0x0563, 0x49, text="TANK FARM", txt=7)
        assert started["id"] >= 1 and started["m"] == "H'0563'" and started["c"] == "H'49'"
        done = api.wait_exchange(started["id"], WAIT_S)
        assert done["result"]["E"] == 0, done
        read = api.wait_exchange(api.start_exchange(0x0563, 0x4A, recv=20, txt=7)["id"], WAIT_S)
        result = read["result"]
        assert set(result) >= {"V", "S", "E", "words", "data"}
        assert result["E"] == 0 and result["S"] == 20
        assert bytes.fromhex(result["data"]).startswith(b"TANK FARM")
        assert result["words"][0] == 0x4154  # "TA", as the console shows it
        with pytest.raises(ControlError) as info:
            api.exchange(10_000)
        assert info.value.status == 404


SCRIPT = """\
help read
faults 5
tes 2 faults
write W100 30
read W100
fault 5 open_3 on
fault 5 open_3 off
input 5 1 12mA
tes 1 input 2 true
leds 7
status 9
"""


def test_the_attached_console_prints_what_the_stand_alone_one_prints(
    plant: Running, tmp_path: Path
) -> None:
    script = tmp_path / "script.txt"
    script.write_text(SCRIPT)
    plant_file = default_plant_copy(tmp_path)

    def console(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "fieldtwin", "console", *args, "-f", str(script)],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=ROOT,
            check=False,
        )

    alone = console(str(plant_file), "--speed", "max")
    attached = console("--attach", plant.url)
    assert alone.returncode == attached.returncode == 2  # `status 9`: no module there
    assert attached.stdout == alone.stdout
    assert attached.stderr == alone.stderr
    assert "script.txt:11: status 9:" in attached.stderr
    assert attached.stdout.count("\n") > 20


def test_malformed_requests_get_4xx_and_the_plant_keeps_serving_modbus(
    plant: Running, master: ModbusTcpClient
) -> None:
    http = httpx.Client(base_url=plant.url, timeout=WAIT_S)
    cases = [
        ("PUT", "/devices/tes1/objects/0", {"json": {"value": "ten"}}, 422, "body.value"),
        ("PUT", "/devices/tes1/objects/0", {"json": {"value": 70000}}, 422, "body.value"),
        ("PUT", "/devices/tes1/objects/0", {"json": {"value": 1, "extra": 2}}, 422, "body.extra"),
        ("PUT", "/devices/tes9/inputs/3", {"json": {"value": True}}, 404, None),
        ("PUT", "/devices/tes1/inputs/99", {"json": {"value": True}}, 404, None),
        ("PUT", "/devices/5/faults/smoke", {"json": {}}, 404, None),
        ("PUT", "/devices/tes1/inputs/3", {"json": {"value": "maybe"}}, 400, None),
        (
            "PUT",
            "/devices/tes2/inputs/a0",
            {"json": {"signal": {"kind": "csv", "file": "/etc/passwd"}}},
            400,
            None,
        ),
        ("POST", "/clock/step", {"json": {"ms": -5}}, 422, "body.ms"),
        ("PUT", "/clock/speed", {"json": {"speed": "warp"}}, 422, "body.speed"),
        (
            "POST",
            "/exchanges",
            {"content": b'{"m": 1379, "c": ', "headers": {"content-type": "application/json"}},
            422,
            None,
        ),
        (
            "POST",
            "/console",
            {"content": b"\xff\xfe not json", "headers": {"content-type": "application/json"}},
            400,
            "body",
        ),
        ("GET", "/exchanges/abc", {}, 422, "path.ident"),
    ]
    for method, path, kwargs, status, field in cases:
        reply = http.request(method, path, **kwargs)  # type: ignore[arg-type]
        assert reply.status_code == status, (method, path, reply.text)
        body = reply.json()
        assert body["error"], body
        if field is not None:
            assert body["field"] == field, body
    big = http.put(
        "/devices/tes1/objects/0",
        content=b"[" + b"1," * 5_000_000 + b"1]",
        headers={"content-type": "application/json"},
    )
    assert big.status_code == 413
    assert "65536" in big.json()["error"]
    assert http.get("/plant").status_code == 200
    assert word(master, 1, DIRECT_0) is not None and word(master, 2, 0x000) is not None
    assert plant.alive()
    http.close()


def test_openapi_schema_names_the_resources(plant: Running) -> None:
    schema = httpx.get(f"{plant.url}/openapi.json", timeout=WAIT_S).json()
    paths = set(schema["paths"])
    for path in (
        "/plant",
        "/devices/{ident}/inputs/{name}",
        "/devices/{ident}/faults/{name}",
        "/devices/{ident}/objects/{name}",
        "/exchanges",
        "/clock/step",
        "/console",
    ):
        assert path in paths


def test_the_clock_pauses_steps_and_resumes(plant: Running) -> None:
    with Client(plant.url) as api:
        paused = api.pause()
        try:
            assert paused["paused"] is True
            assert api.clock()["t_us"] == paused["t_us"]
            stepped = api.step(250)
            assert stepped["t_us"] == paused["t_us"] + 250_000
            ran = api.run_until(stepped["t_s"] + 0.5)
            assert ran["t_us"] == stepped["t_us"] + 500_000
            assert api.set_speed(2)["speed"] == 2
        finally:
            api.set_speed(1)
            resumed = api.resume()
        assert resumed["paused"] is False


def test_the_event_stream_filters_by_kind_and_device(plant: Running) -> None:
    with Client(plant.url) as api:
        events = api.events(["object"], ["tes1"], timeout_s=WAIT_S)
        api.set_input("tes1", "4", True)
        first = next(events)
        assert first["kind"] == "object" and first["device"].endswith(" 1")
        clocks = api.events(["clock"], timeout_s=WAIT_S)
        api.pause()
        api.resume()
        seen = [next(clocks)["what"] for _ in range(2)]
        assert seen == ["paused", "resumed"]
        events.close()
        clocks.close()


def test_drop_connections_closes_the_masters_connection_and_it_can_reconnect(
    plant: Running,
) -> None:
    master = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=1, retries=0)
    assert master.connect()  # type: ignore[no-untyped-call]
    try:
        assert word(master, 2, 0x000) is not None
        with Client(plant.url) as api:
            assert "drop_connections" in [f["name"] for f in api.faults("tes2")]
            api.set_fault("tes2", "drop_connections")
            assert word(master, 2, 0x000) is None  # this connection was closed under it
            fresh = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=1, retries=0)
            assert fresh.connect()  # type: ignore[no-untyped-call]
            try:
                assert word(fresh, 2, 0x000) is not None  # the endpoint still listens
            finally:
                fresh.close()  # type: ignore[no-untyped-call]
    finally:
        master.close()  # type: ignore[no-untyped-call]


def test_register_writes_and_dem_messages_are_events(
    plant: Running, master: ModbusTcpClient
) -> None:
    with Client(plant.url) as api:
        registers = api.events(["register"], timeout_s=WAIT_S)
        assert not master.write_register(0x000, 0, device_id=2).isError()
        event = next(registers)
        assert (event["device"].split()[-1], event["address"], event["values"]) == ("2", 0, [0])
        registers.close()
        dem = api.events(["dem"], ["4"], timeout_s=90)  # time set by the pulse at 60 s
        first = next(dem)
        assert first["type"] in ("change", "overall") and first["stamp"].startswith("1994-07-15")
        dem.close()
