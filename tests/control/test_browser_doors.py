"""A web page the plant was not given cannot drive it (docs/control.md, "Security model"):
Origin, Host (DNS rebinding), JSON bodies (no HTML form), Sec-Fetch-Site; strict types,
seeded signals, Allow, and Swagger UI from the package.  A real `fieldtwin run`."""

from __future__ import annotations

import json
import re
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, cast

import httpx
import pytest
from fastapi import Request
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from fieldtwin.control.app import _validation
from fieldtwin.control.dashboard import STATIC
from fieldtwin.control.schemas import ObjectBody, SpeedBody, StepBody
from tests.control.plantproc import ROOT, Running, default_plant_copy, fieldtwin_run

EVIL = "http://evil.example"
ALLOWED = "http://localhost:3000"


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    plant = default_plant_copy(tmp_path_factory.mktemp("doors"))
    with fieldtwin_run(plant, "--allow-origin", ALLOWED) as running:
        yield running


@pytest.fixture()
def http(plant: Running) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=plant.url, timeout=10) as client:
        yield client


def ws_url(plant: Running) -> str:
    return plant.url.replace("http://", "ws://") + "/events?kind=clock"


def test_another_origin_cannot_change_the_plant_nor_listen(
    plant: Running, http: httpx.Client
) -> None:
    for method, path, body in [
        ("POST", "/clock/pause", {}),
        ("PUT", "/clock/speed", {"speed": 2}),
        ("POST", "/devices/tes1/power-cycle", {}),
        ("DELETE", "/devices/tes1/faults/late_answer", {}),
        ("POST", "/console", {"line": "status 5"}),
    ]:
        refused = http.request(method, path, json=body, headers={"Origin": EVIL})
        assert refused.status_code == 403, (path, refused.text)
        assert refused.json()["field"] == "origin" and EVIL in refused.json()["error"]
        assert http.request(method, path, json=body, headers={"Origin": "null"}).status_code == 403
    assert http.get("/clock").json()["paused"] is False  # nothing was paused
    with pytest.raises(InvalidStatus) as info:
        connect(ws_url(plant), origin=EVIL, open_timeout=10)  # type: ignore[arg-type]
    assert info.value.response.status_code == 403
    # the plant's own pages, and an origin given with --allow-origin, may
    with connect(ws_url(plant), origin=plant.url, open_timeout=10):  # type: ignore[arg-type]
        pass
    own = http.post("/clock/pause", json={}, headers={"Origin": plant.url})
    assert own.status_code == 200
    allowed = http.post("/clock/resume", json={}, headers={"Origin": ALLOWED})
    assert allowed.status_code == 200 and allowed.json()["paused"] is False
    assert allowed.headers["access-control-allow-origin"] == ALLOWED
    preflight = http.options(
        "/clock/pause",
        headers={
            "Origin": ALLOWED,
            "Access-Control-Request-Method": "POST",
            "Access-Control-Request-Headers": "content-type",
        },
    )
    assert preflight.status_code == 200
    assert "POST" in preflight.headers["access-control-allow-methods"]
    assert http.get("/plant", headers={"Origin": EVIL}).status_code == 200  # CORS: unreadable
    assert "access-control-allow-origin" not in http.get("/plant", headers={"Origin": EVIL}).headers


def test_a_rebound_host_name_is_refused(plant: Running, http: httpx.Client) -> None:
    for path in ("/plant", "/", "/openapi.json", "/static/dashboard.js"):
        refused = http.get(path, headers={"Host": "rebind.example"})
        assert refused.status_code == 400, path
        assert refused.json()["field"] == "host"
        assert "rebind.example" in refused.json()["error"]
    port = plant.url.rsplit(":", 1)[1]
    assert http.post("/clock/pause", json={}, headers={"Host": f"evil:{port}"}).status_code == 400
    for host in (f"localhost:{port}", f"127.0.0.1:{port}", f"LOCALHOST:{port}", "[::1]"):
        assert http.get("/clock", headers={"Host": host}).status_code == 200, host
    assert websocket_status(plant, "rebind.example") == 403  # refused before its accept
    assert websocket_status(plant, f"127.0.0.1:{port}") == 101


def websocket_status(plant: Running, host: str) -> int:
    """The status a WebSocket handshake to /events with this Host header gets."""
    port = int(plant.url.rsplit(":", 1)[1])
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.sendall(
            f"GET /events HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
            "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
            "Sec-WebSocket-Version: 13\r\n\r\n".encode()
        )
        head = sock.recv(4096).decode("latin-1")
    return int(head.split()[1])


def test_a_form_post_is_refused_and_a_bodyless_route_takes_an_empty_object(
    http: httpx.Client,
) -> None:
    form = http.post("/clock/pause", data={"x": "1"})
    assert form.status_code == 415
    assert form.json()["field"] == "content-type" and "application/json" in form.json()["allowed"]
    text = {"content-type": "text/plain"}
    assert http.post("/clock/pause", content=b"{}", headers=text).status_code == 415
    assert http.post("/clock/pause").status_code == 415  # no body, no content type
    assert http.delete("/devices/tes1/faults/late_answer").status_code == 415
    assert http.put("/clock/speed", content=b'{"speed": 2}').status_code == 415
    for body in (b"[]", b'{"x": 1}', b"", b"null"):
        wrong = http.post(
            "/clock/pause", content=body, headers={"content-type": "application/json"}
        )
        assert wrong.status_code == 422 and wrong.json()["allowed"] == "{}", body
    assert http.get("/clock").json()["paused"] is False
    ok = http.post(
        "/clock/pause", content=b" {} ", headers={"content-type": "application/json; charset=utf-8"}
    )
    assert ok.status_code == 200 and ok.json()["paused"] is True
    assert http.post("/clock/resume", json={}).json()["paused"] is False
    assert http.get("/plant").headers["x-frame-options"] == "DENY"  # no framing page either


def test_a_request_another_site_makes_is_refused_but_a_link_to_the_page_works(
    http: httpx.Client,
) -> None:
    cross = {"Sec-Fetch-Site": "cross-site", "Sec-Fetch-Mode": "no-cors"}
    refused = http.get("/devices/tes1/objects/0x005", headers=cross)  # a master's read
    assert refused.status_code == 403 and refused.json()["field"] == "origin"
    link = {"Sec-Fetch-Site": "cross-site", "Sec-Fetch-Mode": "navigate"}
    assert http.get("/", headers=link).status_code == 200
    assert http.get("/plant", headers=link).status_code == 403
    own = {"Sec-Fetch-Site": "same-origin", "Sec-Fetch-Mode": "cors"}
    assert http.get("/devices/tes1/objects/0x005", headers=own).status_code == 200


def test_types_are_strict_and_a_seed_stays_an_integer(http: httpx.Client) -> None:
    assert http.post("/exchanges", json={"m": 1379, "c": 74, "txt": False}).status_code == 422
    assert http.post("/clock/step", json={"ms": True}).status_code == 422
    assert http.put("/devices/tes1/objects/0x00A", json={"value": True}).status_code == 422
    assert http.put("/clock/speed", json={"speed": True}).status_code == 422
    assert http.put("/clock/speed", json={"speed": "2"}).status_code == 422
    noise = {"kind": "noise", "base": 5.0, "sigma": 0.5, "seed": 1}
    driven = http.put("/devices/tes2/inputs/a1", json={"signal": noise})
    assert driven.status_code == 200, driven.text
    assert driven.json()["signal"]["seed"] == 1
    assert http.put("/devices/tes2/inputs/a1", json={"value": "2.5V"}).status_code == 200


def test_a_405_lists_every_method_of_the_path(http: httpx.Client) -> None:
    wrong = http.get("/devices/tes1/faults/late_answer")
    assert wrong.status_code == 405 and wrong.headers["allow"] == "DELETE, PUT"
    assert http.post("/devices/tes1/objects/0x005", json={}).headers["allow"] == "GET, PUT"


def test_swagger_ui_comes_from_the_package(http: httpx.Client) -> None:
    page = http.get("/docs")
    assert page.status_code == 200
    assert not re.search(r"(src|href)=\"https?://", page.text), page.text  # no CDN
    assert "validatorUrl" in page.text  # no badge fetched from the validator's site
    for path in re.findall(r'(?:src|href)="(/static/[^"?]+)', page.text):
        assert http.get(path).status_code == 200, path
    vendor = STATIC / "vendor" / "swagger-ui"
    assert "Apache License" in (vendor / "LICENSE").read_text()
    assert http.get("/redoc").status_code == 404  # ReDoc would come from a CDN: not served


def test_an_allowed_origin_must_be_an_origin(tmp_path: Path) -> None:
    done = subprocess.run(
        [
            *(sys.executable, "-m", "fieldtwin", "run", str(default_plant_copy(tmp_path))),
            *("--no-live", "--control-port", "0", "--allow-origin", "http://x.example/path"),
        ],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 2, done.stderr
    assert "--allow-origin 'http://x.example/path': not a web origin" in done.stderr
    assert "Traceback" not in done.stderr


def _refusal(model: type[BaseModel], body: dict[str, object]) -> dict[str, Any]:
    try:
        model.model_validate(body)
    except ValidationError as exc:
        errors = [{**e, "loc": ("body", *e["loc"])} for e in exc.errors()]
        response = _validation(cast(Request, None), RequestValidationError(errors))
        answer: dict[str, Any] = json.loads(bytes(response.body))
        return answer
    raise AssertionError(f"{body} was accepted")


def test_a_validation_error_says_what_is_wrong_and_what_is_allowed() -> None:
    """`error` tells what pydantic found, `allowed` what the field takes, in words."""
    speed = _refusal(SpeedBody, {"speed": "fast"})
    assert speed["field"] == "body.speed" and speed["allowed"] == "a number or 'max'", speed
    assert speed["error"] == 'body.speed: "fast" is not allowed', speed
    assert _refusal(StepBody, {"ms": -1})["allowed"] == "a value > 0.0"
    assert _refusal(StepBody, {})["allowed"] == "a value (the field is required)"
    assert _refusal(StepBody, {})["error"] == "body.ms: required"
    value = _refusal(ObjectBody, {"value": "ten"})
    assert value["error"] == 'body.value: "ten" is not allowed', value
    assert value["allowed"].startswith("a valid integer"), value
