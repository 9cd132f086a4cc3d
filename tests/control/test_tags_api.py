"""Tags and trends over the control API of a real `fieldtwin run` (subprocess), and the
console by tag (POST /console): docs/control.md, "Tags and trends"."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.control.plantproc import Running, fieldtwin_run

WAIT_S = 10.0

PLANT = """
[plant]
name = "tagged"
[run]
speed = 10
[plc]
model = "TSX 87"
[[module]]
type = "TSX DET 805"
rack = 1
slot = 4
inputs = { 0 = 1 }
[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:0"
inputs = { a0 = 5.0 }
[dashboard]
trends = ["level"]
[[tag]]
name = "level"
object = "W0"
unit = "m"
scale = [0, 10000, 0, 10]
description = "tank level"
[[tag]]
name = "pump3.run"
device = "14"
input = "0"
[[tag]]
name = "pressure"
device = "tes2"
input = "a0"
unit = "bar"
scale = [0, 10, 0, 6]
[[tag]]
name = "filter"
device = "tes2"
register = "H'00A'"
"""


@pytest.fixture(scope="module")
def tagged(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    path = tmp_path_factory.mktemp("tags") / "plant.toml"
    path.write_text(PLANT)
    with fieldtwin_run(path) as running:
        yield running


def client(running: Running) -> httpx.Client:
    return httpx.Client(base_url=running.url, timeout=WAIT_S)


def test_tags_are_listed_with_their_source_and_value_in_their_unit(tagged: Running) -> None:
    with client(tagged) as http:
        listed = http.get("/tags").json()
        assert [t["name"] for t in listed] == ["level", "pump3.run", "pressure", "filter"]
        pressure = http.get("/tags/pressure").json()
        assert pressure["source"] == {"device": "tes2", "input": "a0"}
        assert pressure["source_text"] == "tes2 input a0"
        assert pressure["unit"] == "bar" and pressure["scale"] == [0, 10, 0, 6]
        assert pressure["raw"] == pytest.approx(5.0, abs=0.01)
        assert pressure["value"] == pytest.approx(3.0, abs=0.01)
        assert pressure["text"].endswith(" bar")
        assert http.get("/tags/FILTER").json()["source"] == {"device": "tes2", "register": "H'00A'"}
        missing = http.get("/tags/nope")
        assert missing.status_code == 404
        assert (
            "no tag 'nope' (allowed: level, pump3.run, pressure, filter" in missing.json()["error"]
        )
        assert "/tags/{name}" in http.get("/openapi.json").json()["paths"]


def test_a_tag_is_written_and_set_in_its_unit(tagged: Running) -> None:
    with client(tagged) as http:
        written = http.put("/tags/level", json={"value": 2.5})
        assert written.status_code == 200, written.text
        assert (written.json()["value"], written.json()["raw"]) == (2.5, 2500)
        assert http.get("/tags/W0").json()["name"] == "level"  # the object, by its tag
        set_input = http.put("/tags/pressure", json={"value": 4.5}).json()
        assert set_input["raw"] == pytest.approx(7.5, abs=0.01)
        assert set_input["value"] == pytest.approx(4.5, abs=0.01)
        refused = http.put("/tags/nope", json={"value": 1})
        assert refused.status_code == 404
        mismatch = http.put("/tags/pressure", json={"value": True})  # an analog input
        assert mismatch.status_code == 409 and "not a number" in mismatch.json()["error"]
        bad = http.put("/tags/level", json={"value": [1]})
        assert bad.status_code == 422 and bad.json()["field"].startswith("body.value")


def test_the_console_reads_and_sets_by_tag(tagged: Running) -> None:
    with client(tagged) as http:
        http.put("/tags/level", json={"value": 4})
        read = http.post("/console", json={"line": "read level W0"}).json()
        assert read == {"lines": ["level = 4 m  (W0)", "W0 = 4000"], "error": None}
        done = http.post("/console", json={"line": "input pump3.run off"}).json()
        assert done["error"] is None and done["lines"] == ["input pump3.run 0 = off"]
        deadline = time.monotonic() + WAIT_S
        while http.get("/tags/pump3.run").json()["value"] is not False:  # the next scan
            assert time.monotonic() < deadline, "I14,0 never read off"
            time.sleep(0.05)
        wrong = http.post("/console", json={"line": "read nope"}).json()
        assert "neither an object nor a tag" in wrong["error"]


def test_a_trend_keeps_its_history_from_before_it_was_asked(tagged: Running) -> None:
    with client(tagged) as http:
        trends = http.get("/trends").json()
        assert trends["defaults"] == ["level"] and "pressure" in trends["series"]
        deadline = time.monotonic() + WAIT_S
        while len(points := http.get("/trends/pressure").json()["points"]) < 4:
            assert time.monotonic() < deadline, f"too few points: {points}"
            time.sleep(0.1)
        times = [p[0] for p in points]
        assert times == sorted(times) and times[0] < times[-1]
        assert all(p[1] is not None and 2.9 <= p[1] <= 4.6 for p in points)  # bar: 3, or 4.5
        since = http.get("/trends/pressure", params={"since": times[-2]}).json()
        assert since["unit"] == "bar" and since["points"][0][0] > times[-2]
        # an object asked for later is kept from then on
        asked = http.get("/trends/W1").json()
        assert asked["series"] == "W1" and len(asked["points"]) == 1
        assert "W1" in http.get("/trends").json()["series"]
        assert http.get("/trends/nope").status_code == 404


def test_a_plant_file_with_a_wrong_tag_is_refused_naming_the_field(tmp_path: Path) -> None:
    import subprocess
    import sys

    path = tmp_path / "plant.toml"
    path.write_text(PLANT.replace("register = \"H'00A'\"", "register = \"H'FFF'\""))
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "run", str(path), "--no-live", "--duration", "1"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    assert "plant.toml: tag[3].register: \"H'FFF'\" is no register of TES 8EA tes2" in done.stderr
