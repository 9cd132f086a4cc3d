"""The dashboard is served by `fieldtwin run` itself, every file from the package (no CDN),
and ``GET /dashboard/state`` is in the API's schema; no browser needed here."""

from __future__ import annotations

import json
import re
import urllib.error
import urllib.request
from pathlib import Path

import httpx

from fieldtwin.control.dashboard import STATIC, TEMPLATES
from tests.control.plantproc import Running, default_plant_copy, fieldtwin_run


def get(url: str, token: str | None = None) -> tuple[int, str, str]:
    request = urllib.request.Request(url)
    if token:
        request.add_header("Authorization", f"Bearer {token}")
    try:
        with urllib.request.urlopen(request, timeout=10) as answer:
            return answer.status, answer.headers.get("content-type", ""), answer.read().decode()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.headers.get("content-type", ""), exc.read().decode()


def test_the_page_its_files_and_the_state_come_from_the_plant(plant: Running) -> None:
    assert f"dashboard: {plant.url}/" in plant.lines
    index = plant.lines.index(f"dashboard: {plant.url}/")
    assert plant.lines[index - 1] == f"control: {plant.url}"  # next to the control: line
    status, kind, html = get(f"{plant.url}/")
    assert status == 200 and kind.startswith("text/html")
    assert "http://" not in html and "https://" not in html  # nothing from elsewhere
    sources = re.findall(r'(?:src|href)="(/static/[^"?]+)', html)
    assert {"/static/dashboard.js", "/static/vendor/uplot/uPlot.iife.min.js"} <= set(sources)
    for path in sources:
        status, kind, text = get(f"{plant.url}{path}")
        assert status == 200 and text, path
        assert ("javascript" in kind) if path.endswith(".js") else ("css" in kind), (path, kind)
        assert "//cdn" not in text and "googleapis" not in text, path
    status, _, schema = get(f"{plant.url}/openapi.json")
    paths = json.loads(schema)["paths"]
    assert "/dashboard/state" in paths and "/" not in paths
    status, _, body = get(f"{plant.url}/dashboard/state")
    state = json.loads(body)
    assert [m["id"] for m in state["modules"]] == ["4", "5", "7", "14", "16", "17"]
    assert [t["id"] for t in state["tes"]] == ["tes1", "tes2"]
    assert state["plc"] == {
        "model": "TSX 87", "running": True, "mode": "RUN", "fault": None, "scan_ms": 10.0,
        "program": state["plc"]["program"],
    }  # fmt: skip
    dst = next(m for m in state["modules"] if m["id"] == "16")
    assert dst["i_bits"] is None and isinstance(dst["o_bits"], int)  # an output module
    det = next(m for m in state["modules"] if m["id"] == "14")
    assert det["o_bits"] is None and det["i_bits"] & 1 == 1  # I14,0 on (the plant file)
    tes2 = next(t for t in state["tes"] if t["id"] == "tes2")
    a1 = next(a for a in tes2["analog"] if a["input"] == "a1")
    assert a1["level"] == 2.5 and a1["unit"] == "V"
    assert [led for led, _ in tes2["leds"]] == ["Pwr", "Run", "Prm", "Wdg"]
    status, _, _ = get(f"{plant.url}/static/../dashboard.py")
    assert status == 404


def test_the_vendored_chart_library_ships_with_its_licence() -> None:
    vendor = STATIC / "vendor" / "uplot"
    assert "MIT" in (vendor / "LICENSE").read_text()
    assert (vendor / "uPlot.iife.min.js").stat().st_size > 10_000
    assert "{{ suffix }}" in (TEMPLATES / "dashboard.html").read_text()


def test_with_a_token_the_page_and_its_files_need_it(tmp_path: Path) -> None:
    with fieldtwin_run(default_plant_copy(tmp_path), "--control-token", "s3cret") as running:
        assert f"dashboard: {running.url}/?token=s3cret" in running.lines
        assert get(f"{running.url}/")[0] == 401
        assert get(f"{running.url}/static/dashboard.js")[0] == 401
        first = httpx.get(f"{running.url}/?token=s3cret", timeout=10)
        assert first.status_code == 200
        html = first.text
        # R13: the token is no longer written into the page's file URLs (it would land in
        # logs and history); the first load keeps it in an HttpOnly SameSite=Strict cookie
        assert 'src="/static/dashboard.js?v=' in html and "s3cret" not in html
        cookie = first.headers["set-cookie"]
        port = running.url.rsplit(":", 1)[1]
        assert cookie.startswith(f"fieldtwin_token_{port}=s3cret;")
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
        jar = {f"fieldtwin_token_{port}": "s3cret"}
        for path in ("/static/dashboard.js", "/dashboard/state", "/"):
            assert httpx.get(running.url + path, cookies=jar, timeout=10).status_code == 200
        # ?token= is taken on the first page load and the WebSocket only, not on every route
        assert get(f"{running.url}/static/dashboard.js?token=s3cret")[0] == 401
        assert get(f"{running.url}/dashboard/state?token=s3cret")[0] == 401
        assert get(f"{running.url}/dashboard/state", token="s3cret")[0] == 200
