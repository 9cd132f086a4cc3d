"""Issue 21 item 2 through the control API: every analog TES takes "3V" and "12mA".

A real `fieldtwin run` (bounded waits): ``PUT /devices/{tes}/inputs/a1`` with
``{"value": "3V"}`` and ``{"value": "12mA"}`` on a TES 4EA, 8EA and 8ESA; the
analog input word then reads the points of 3 V of 10 V and 12 mA of 20 mA.
"""

from __future__ import annotations

import time
from pathlib import Path

import httpx

from tests.control.plantproc import fieldtwin_run

MODELS = ("TES 4EA", "TES 8EA", "TES 8ESA")
WAIT_S = 20.0


def _plant(tmp_path: Path) -> Path:
    path = tmp_path / "plant.toml"
    path.write_text(
        "".join(
            f'[[tes]]\nmodel = "{m}"\nendpoint = "tcp://127.0.0.1:0"\nslave = {i + 1}\n\n'
            for i, m in enumerate(MODELS)
        )
    )
    return path


def _word(http: httpx.Client, device: str, address: int, wanted: int) -> int:
    deadline = time.monotonic() + WAIT_S  # the TES samples every 32/64 ms, paced x1
    while True:
        reply = http.get(f"/devices/{device}/objects/{address}", params={"peek": "true"})
        value = int(reply.json()["value"])
        if value == wanted or time.monotonic() > deadline:
            return value
        time.sleep(0.05)


def test_put_volts_and_milliamps_on_every_analog_tes(tmp_path: Path) -> None:
    with fieldtwin_run(_plant(tmp_path)) as running:
        http = httpx.Client(base_url=running.url, timeout=WAIT_S)
        for n in range(1, len(MODELS) + 1):
            device = f"tes{n}"
            volts = http.put(f"/devices/{device}/inputs/a1", json={"value": "3V"})
            assert volts.status_code == 200, volts.text
            amps = http.put(f"/devices/{device}/inputs/a2", json={"value": "12mA"})
            assert amps.status_code == 200, amps.text
            assert _word(http, device, 0x004, 307) == 307  # 3 V of 10 V: 1023 points
            assert _word(http, device, 0x005, 614) == 614  # 12 mA of 20 mA
        bad = http.put("/devices/tes1/inputs/a1", json={"value": "3 volts"})
        assert bad.status_code == 400 and "'3 volts' not allowed" in bad.text
