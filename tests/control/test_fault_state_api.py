"""Issue 21 through a real `fieldtwin run`: fault state, outputs, faults refused by port kind.

As a user with curl would see it (httpx, bounded waits): ``GET /devices/{id}/faults``
gives each fault with ``active`` and ``params``; ``GET /devices/{id}`` has
``active_faults`` and ``outputs``; ``GET /devices/{id}/outputs`` exists (404 for an
unknown device, declared in the OpenAPI document); ``bad_crc`` on a TES reached
only over Modbus TCP is a 400 naming the port kinds where it applies.
"""

from __future__ import annotations

from pathlib import Path

import httpx

from tests.control.plantproc import fieldtwin_run

PLANT = """
[[tes]]
model = "TES 32EST"
endpoint = "tcp://127.0.0.1:0"
slave = 1

[[tes]]
model = "TES 4SA"
endpoint = "tcp://127.0.0.1:0"
slave = 2
"""


def test_fault_state_outputs_and_port_kinds_over_http(tmp_path: Path) -> None:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT)
    with fieldtwin_run(path) as running:
        http = httpx.Client(base_url=running.url, timeout=20)
        faults = {f["name"]: f for f in http.get("/devices/tes1/faults").json()}
        assert faults["late_answer"]["active"] is False and faults["late_answer"]["params"] == {}
        assert "bad_crc" not in faults
        put = http.put("/devices/tes1/faults/late_answer", json={"params": {"ms": 200}})
        assert put.status_code == 200, put.text
        faults = {f["name"]: f for f in http.get("/devices/tes1/faults").json()}
        assert faults["late_answer"] == {**faults["late_answer"], "active": True}
        assert faults["late_answer"]["params"] == {"ms": 200}
        status = http.get("/devices/tes1").json()
        assert status["active_faults"] == {"late_answer": {"ms": 200}}
        assert [o["name"] for o in status["outputs"]] == [str(i) for i in range(16)]
        console = http.post("/console", json={"line": "tes 1 faults"}).json()
        assert "* late_answer active ms=200" in console["lines"]
        cleared = http.request("DELETE", "/devices/tes1/faults/late_answer", json={})
        assert cleared.status_code == 200
        assert http.get("/devices/tes1").json()["active_faults"] == {}

        bad = http.put("/devices/tes1/faults/bad_crc", json={"active": True})
        assert bad.status_code == 400, bad.text
        assert "RTU over TCP or RTU line" in bad.text and "Modbus TCP" in bad.text

        assert http.put("/devices/tes2/objects/H'014'", json={"value": 0x4000}).status_code == 200
        outputs = {o["name"]: o for o in http.get("/devices/tes2/outputs").json()}
        assert outputs["a0"]["unit"] == "V" and outputs["a0"]["raw"] == 0x4000
        assert 0 < outputs["a0"]["value"] <= 10
        missing = http.get("/devices/tes9/outputs")
        assert missing.status_code == 404 and "tes1" in missing.text
        spec = http.get("/openapi.json").json()
        assert "404" in spec["paths"]["/devices/{ident}/outputs"]["get"]["responses"]
