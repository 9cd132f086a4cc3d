"""The made-up device on the dashboard: its fault with a parameter (offered where its
loop is, with its hint, lit when set with curl) and its output in volts, from a real
`fieldtwin run` that imports tests/devices/madeup.py first (no edit outside it)."""

from __future__ import annotations

import contextlib
import json
import queue
import re
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from typing import Any

import pytest

from tests.control.plantproc import ROOT, Running
from tests.dashboard.pages import open_controls, open_dashboard
from tests.devices.madeup import LEVEL

START_S = 60.0
RUN = "import sys, tests.devices.madeup; from fieldtwin.cli import main; sys.exit(main())"
PLANT = f"""
[plc]
model = "TSX 87"

[[module]]
type = "{LEVEL}"
slot = 3
loop = "4-20"
inputs = {{ "0" = 2.0 }}
"""


def _read(stream: Any, lines: queue.Queue[str]) -> None:
    with contextlib.suppress(ValueError, OSError):
        for line in stream:
            lines.put(line)


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    path = tmp_path_factory.mktemp("madeup") / "plant.toml"
    path.write_text(PLANT)
    proc = subprocess.Popen(
        [sys.executable, "-c", RUN, "run", str(path), "--no-live", "--control-port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    running = Running(proc)
    try:
        assert proc.stdout is not None
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=_read, args=(proc.stdout, lines), daemon=True).start()
        deadline = time.monotonic() + START_S
        while not running.lines or not running.lines[-1].startswith("attach: "):
            assert time.monotonic() < deadline, f"no start within {START_S} s: {running.lines}"
            assert proc.poll() is None, f"fieldtwin run ended: {running.lines}"
            with contextlib.suppress(queue.Empty):
                line = lines.get(timeout=0.5).rstrip("\n")
                running.lines.append(line)
                if m := re.match(r"control: (http://\S+)$", line):
                    running.url = m.group(1)
        yield running
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


def _put(plant: Running, path: str, body: object) -> Any:
    request = urllib.request.Request(
        f"{plant.url}{path}",
        data=json.dumps(body).encode(),
        method="PUT",
        headers={"content-type": "application/json"},
    )
    with urllib.request.urlopen(request, timeout=10) as answer:
        return json.load(answer)


def test_the_made_up_device_on_the_dashboard(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#mod-3")
    assert box.locator("button.fault").evaluate_all("bs => bs.map(b => b.dataset.fault)") == [
        "float_stuck",
        "noise",
    ]
    hint = box.locator("button.fault[data-fault=noise] + input.args")
    assert hint.get_attribute("placeholder") == "mv=1"
    _put(plant, "/devices/3/faults/noise", {"params": {"mv": 50}})
    button = "#mod-3 button.fault[data-fault=noise]"
    page.wait_for_function(f"document.querySelector('{button}').classList.contains('active')")
    assert "noise mv=50" in page.locator("#mod-3 [data-f=faults]").inner_text()
    _put(plant, "/devices/3/objects/OW3,0", {"value": 4500})
    page.wait_for_function(
        "document.querySelector('#mod-3 [data-aout=\"0\"]').textContent === '4.500 V'"
    )


def test_its_front_is_drawn_from_its_typed_panel(page: Any, plant: Running) -> None:
    # no layout of its own: the page draws its Device.panel() (reading, unit, flags, fields)
    open_dashboard(page, plant)
    reading = "#mod-3 [data-reading=level]"
    page.wait_for_function(
        f"/^2\\.0[0-9]0 V$/.test(document.querySelector('{reading}')?.textContent)"
    )
    assert page.locator("#mod-3 [data-field=loop]").inner_text() == "4-20"
    _put(plant, "/devices/3/faults/float_stuck", {"active": True})
    flags = "#mod-3 [data-flags=level]"
    page.wait_for_function(f"document.querySelector('{flags}').textContent === 'float_stuck'")
    _put(plant, "/devices/3/faults/float_stuck", {"active": False})
    page.wait_for_function(f"document.querySelector('{flags}').textContent === ''")
