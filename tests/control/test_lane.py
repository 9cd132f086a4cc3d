"""The fast lane of ``PUT .../inputs/NAME`` and ``PUT .../objects/NAME`` (commands) and of
``GET /clock`` (a read from the snapshot) answers exactly as the whole stack (gates,
FastAPI's router, the route) does: the same random requests - valid and invalid bodies,
Content-Types, Host, Origin and Sec-Fetch-Site headers, tokens, paths, methods - sent to a
plant served with the lane and to its twin served without get the same status, headers
and body, and the two plants' doors see the same commands."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import httpx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.control.lane import FastLane
from fieldtwin.control.resources import Control
from fieldtwin.control.server import ControlServer, bind_control
from fieldtwin.control.sim import serve
from fieldtwin.plant import build_plant, read_plant
from fieldtwin.runtime.door import Command
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.runner import Runner

WAIT_S = 10.0
TOKEN = "s3cret-token"
UNCOMPARED = {b"date", b"server"}  # uvicorn's own, the same on both but for the time


@dataclass
class Served:
    """A default plant, its API served (with or without the lane), its commands taken by
    a thread of ours, and every command its door saw."""

    url: str
    port: int
    server: ControlServer
    seen: list[tuple[object, ...]] = field(default_factory=list)

    def before(self, command: Command) -> None:
        pass

    def after(self, command: Command, answer: object, error: BaseException | None) -> None:
        failed = None if error is None else (type(error).__name__, str(error))
        self.seen.append((command.kind, command.name, repr(command.args), repr(answer), failed))


@contextmanager
def served(lane: bool, token: str | None) -> Iterator[Served]:
    plant = build_plant(read_plant(None))
    inbox = Inbox(door=plant.door)
    control = Control(plant, Runner(plant.clock, None), EventBus())
    serve(plant.door, control, control.console.handle)
    sock = bind_control("127.0.0.1", 0, fallback=False)
    server = ControlServer(control, inbox, sock, token, lane=lane)
    stop = threading.Event()

    def take() -> None:
        while not stop.is_set():
            if inbox.wait(0.05):
                inbox.run_pending()

    thread = threading.Thread(target=take, daemon=True)
    thread.start()
    try:
        url = server.start()
        found = Served(url, int(url.rsplit(":", 1)[1]), server)
        plant.door.watch(found)
        yield found
    finally:
        stop.set()
        thread.join(WAIT_S)
        server.close()
        inbox.close()


@pytest.fixture(scope="module")
def twins() -> Iterator[dict[bool, tuple[Served, Served]]]:
    """By whether a token is set: the plant with the lane, and its twin without."""
    with (
        served(True, None) as lane,
        served(False, None) as stack,
        served(True, TOKEN) as lane_token,
        served(False, TOKEN) as stack_token,
    ):
        yield {False: (lane, stack), True: (lane_token, stack_token)}


IDENTS = ["tes1", "tes2", "5", "4", "7", "tes9", "tes1@2", "x y"]
INPUTS = ["3", "0", "15", "99", "a1", "x"]
OBJECTS = ["0x00A", "0x005", "10", "filter_0", "IW5,0", "OW5,1", "W4", "nope"]
VALUES = st.one_of(
    st.booleans(),
    st.integers(-5, 70_000),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["12mA", "2.5V", "on", "off", "true", "1", "", "x" * 65]),
    st.text(max_size=8),
    st.none(),
    st.lists(st.integers(0, 3), max_size=2),
)
SIGNALS = st.sampled_from(
    [
        {"kind": "sine", "offset": 5.0, "amplitude": 2.0, "period_s": 30},
        {"kind": "square", "period_s": 2},
        {"kind": "csv", "file": "x.csv"},
        {"kind": "nope"},
        {},
    ]
)
RAW_BODIES = st.sampled_from(
    [
        b"",
        b"{",
        b"not json",
        b"{}",
        b"[]",
        b"null",
        b'{"value": NaN}',
        b'{"value": Infinity}',
        b'{"value": 1e400}',
        b'{"value": 7.0}',
        b'{"value": 1, "value": true}',
        b'{"value": "\\ud800"}',
        b'{"value": 12345678901234567890123}',
        b' {"value": true} ',
        b'{"value": true}\n',
        b"\xff\xfe",
        '{"value": true}'.encode("utf-16"),
        b'{"valu": 1}',
        b'{"value": "' + b"x" * 70_000 + b'"}',
    ]
)
BODIES = st.one_of(
    st.builds(lambda v: json.dumps({"value": v}).encode(), VALUES),
    st.builds(lambda s: json.dumps({"signal": s}).encode(), SIGNALS),
    st.builds(lambda v, s: json.dumps({"value": v, "signal": s}).encode(), VALUES, SIGNALS),
    RAW_BODIES,
)
PATHS = st.one_of(
    st.builds(
        lambda d, i: f"/devices/{d}/inputs/{i}", st.sampled_from(IDENTS), st.sampled_from(INPUTS)
    ),
    st.builds(
        lambda d, o: f"/devices/{d}/objects/{o}", st.sampled_from(IDENTS), st.sampled_from(OBJECTS)
    ),
    st.sampled_from(
        [
            "/devices/tes1/inputs/3/",
            "/devices/tes1/inputs",
            "/devices/tes1/objects/0x00A?peek=true",
            "/devices/tes1/inputs/3?token=" + TOKEN,
            "/devices//inputs/3",
            "/clock",
            "/tags/tank1.flow",
        ]
    ),
)


@dataclass(frozen=True)
class Ask:
    """A request as the test draws it; ``headers_for`` writes it for one server."""

    method: str
    path: str
    body: bytes
    content_type: str | None
    host: str
    origin: str | None
    fetch_site: str | None
    token: str | None
    twice: str | None  # a header given twice

    def headers_for(self, port: int) -> list[tuple[str, str]]:
        own = f"127.0.0.1:{port}"
        host = {"own": own, "localhost": f"localhost:{port}"}.get(self.host, self.host)
        headers = [("host", host)]
        if self.content_type is not None:
            headers.append(("content-type", self.content_type))
        if self.origin is not None:
            headers.append(("origin", f"http://{own}" if self.origin == "own" else self.origin))
        if self.fetch_site is not None:
            headers.append(("sec-fetch-site", self.fetch_site))
        if self.token == "bearer":
            headers.append(("authorization", f"Bearer {TOKEN}"))
        elif self.token == "wrong":
            headers.append(("authorization", "Bearer nope"))
        elif self.token == "cookie":
            headers.append(("cookie", f"fieldtwin_token_{port}={TOKEN}"))
        elif self.token == "basic":
            headers.append(("authorization", f"Basic {TOKEN}"))
        if self.twice is not None:
            given = dict(headers).get(self.twice, "application/json")
            headers.append((self.twice, given))
        return headers


ANY = st.builds(
    Ask,
    method=st.sampled_from(["PUT"] * 8 + ["POST", "GET", "DELETE"]),
    path=PATHS,
    body=BODIES,
    content_type=st.sampled_from(
        [
            "application/json",
            "application/json; charset=utf-8",
            "Application/JSON",
            "application/json;charset=UTF-8",
            "application/json, text/plain",
            "text/plain",
            None,
        ]
    ),
    host=st.sampled_from(["own", "localhost", "[::1]", "evil.example"]),
    origin=st.sampled_from([None, "own", "http://evil.example", "null"]),
    fetch_site=st.sampled_from([None, "same-origin", "none", "cross-site"]),
    token=st.sampled_from(["bearer", None, "wrong", "cookie", "basic"]),
    twice=st.sampled_from([None, "content-type", "authorization", "cookie"]),
)
# what the lane answers itself: a valid request (its command may still refuse it)
HAPPY = st.builds(
    Ask,
    method=st.just("PUT"),
    path=st.one_of(
        st.builds(
            lambda d, i: f"/devices/{d}/inputs/{i}",
            st.sampled_from(["tes1", "tes2", "5", "tes9"]),
            st.sampled_from(["3", "0", "a1", "99"]),
        ),
        st.builds(
            lambda d, o: f"/devices/{d}/objects/{o}",
            st.sampled_from(["tes1", "tes2", "5", "tes9"]),
            st.sampled_from(["0x00A", "0x005", "filter_0", "OW5,1", "W4"]),
        ),
    ),
    body=st.one_of(
        st.builds(lambda v: json.dumps({"value": v}).encode(), VALUES),
        st.builds(lambda s: json.dumps({"signal": s}).encode(), SIGNALS),
    ),
    content_type=st.sampled_from(["application/json", "application/json; charset=utf-8"]),
    host=st.sampled_from(["own", "localhost"]),
    origin=st.none(),
    fetch_site=st.none(),
    token=st.sampled_from(["bearer", "cookie"]),
    twice=st.none(),
)
# a read the lane answers itself from the snapshot (GET /clock): no body; a Content-Type
# the gates do not look at on a read
HAPPY_READ = st.builds(
    Ask,
    method=st.just("GET"),
    path=st.sampled_from(["/clock", "/clock?x=1", "/clock?token=" + TOKEN]),
    body=st.just(b""),
    content_type=st.sampled_from([None, None, "application/json", "text/plain"]),
    host=st.sampled_from(["own", "localhost"]),
    origin=st.none(),
    fetch_site=st.none(),
    token=st.sampled_from(["bearer", "cookie"]),
    twice=st.none(),
)
FIELDS = [f for f in Ask.__dataclass_fields__]
# a valid request but for one thing, and anything at all
ONE_OFF = st.builds(
    lambda happy, other, name: replace(happy, **{name: getattr(other, name)}),
    st.one_of(HAPPY, HAPPY_READ),
    ANY,
    st.sampled_from(FIELDS),
)
ASKS = st.one_of(HAPPY, HAPPY_READ, ONE_OFF, ANY)


def _answer(served: Served, http: httpx.Client, ask: Ask) -> tuple[object, ...]:
    reply = http.request(
        ask.method,
        served.url + ask.path,
        content=ask.body if ask.method != "GET" else None,
        headers=ask.headers_for(served.port),
    )
    port = str(served.port).encode()
    headers = [
        (key.lower(), value.replace(port, b"PORT"))
        for key, value in reply.headers.raw
        if key.lower() not in UNCOMPARED
    ]
    return reply.status_code, headers, reply.content.replace(port, b"PORT")


@pytest.mark.parametrize("token", [False, True], ids=["no-token", "token"])
@settings(max_examples=100)
@given(asks=st.lists(ASKS, min_size=1, max_size=3))
def test_the_lane_answers_as_the_whole_stack(
    twins: dict[bool, tuple[Served, Served]], token: bool, asks: list[Ask]
) -> None:
    lane, stack = twins[token]
    with httpx.Client(timeout=WAIT_S) as http:
        for ask in asks:
            seen = len(lane.seen), len(stack.seen)
            assert _answer(lane, http, ask) == _answer(stack, http, ask), ask
            assert lane.seen[seen[0] :] == stack.seen[seen[1] :], ask


def test_the_lane_takes_the_happy_path_only(twins: dict[bool, tuple[Served, Served]]) -> None:
    """The lane answers a valid request itself, a command or the clock's read (what the
    property test compares is the lane's answer, not the stack's twice), and hands on
    what it must not answer."""
    lane, _ = twins[True]
    assert isinstance(lane.server.app, FastLane)
    gate: FastLane = lane.server.app
    good = {"authorization": f"Bearer {TOKEN}", "content-type": "application/json"}
    with httpx.Client(base_url=lane.url, timeout=WAIT_S) as http:
        before = gate.answered
        assert http.put("/devices/tes1/inputs/3", json={"value": True}, headers=good).json() == {
            "device": "tes1",
            "input": "3",
            "value": True,
        }
        reply = http.put("/devices/tes1/objects/0x00A", json={"value": 4}, headers=good)
        assert reply.json()["value"] == 4
        assert (
            http.put("/devices/tes9/inputs/3", json={"value": 1}, headers=good).status_code == 404
        )
        assert gate.answered == before + 3  # the 404 too: the command ran and refused it
        clock = http.get("/clock", headers={"authorization": f"Bearer {TOKEN}"})
        assert clock.status_code == 200 and clock.json()["t_us"] == 0
        assert gate.answered == before + 4  # a read from the snapshot
        bearer = {"authorization": f"Bearer {TOKEN}"}
        assert http.get("/clock").status_code == 401  # no token
        assert http.get("/clock", headers={**bearer, "sec-fetch-site": "cross-site"}).is_error
        http.get("/clock", headers={**bearer, "origin": "http://evil.example"})  # CORS's
        http.request("GET", "/clock", headers=bearer, content=b"{}")  # a body on a read
        assert gate.answered == before + 4
        for refused, headers in (
            ({"value": True}, {"content-type": "application/json"}),  # no token: 401
            ({"valu": True}, good),  # not the route's body: 422
            ({"value": True}, {**good, "origin": "http://evil.example"}),  # 403
            ({"value": True}, {**good, "content-type": "text/plain"}),  # 415
        ):
            status = http.put("/devices/tes1/inputs/3", json=refused, headers=headers).status_code
            assert status in (401, 403, 415, 422)
        assert gate.answered == before + 4
