"""``fieldtwin.client``: a running plant's control API from Python, with the API's verbs.

    from fieldtwin.client import Client

    with Client("http://127.0.0.1:8520") as plant:
        plant.set_input("tes1", "2", True)
        plant.set_fault("tes1", "late_answer", ms=200)
        print(plant.read("5", "IW5,0"), plant.console("status 5").lines)

A refused request raises :class:`ControlError` (its ``status`` and the API's
``error`` message); a plant that cannot be reached raises it too (status 0), and
an answer that does not fit its model (fieldtwin.control.replies, the models the
server answers with) raises it with status 502.  Each verb returns the answer's
JSON as before (a dict, a list), checked against its model.
"""

from __future__ import annotations

import json
import time
from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import TracebackType
from typing import TYPE_CHECKING, Any
from urllib.parse import quote, urlencode, urlsplit

import httpx
from pydantic import BaseModel, TypeAdapter, ValidationError

from fieldtwin.control import replies
from fieldtwin.errors import FieldtwinError

if TYPE_CHECKING:
    from websockets.sync.client import ClientConnection

DEFAULT_TIMEOUT_S = 30.0
DEFAULT_MODE_WAIT_S = 60.0  # how long step/run_until/power_break wait for the mode's end


class ControlError(FieldtwinError):
    """The API refused a request (``status`` 4xx/5xx) or could not be reached (0)."""

    def __init__(self, status: int, message: str, body: object = None) -> None:
        super().__init__(message)
        self.status = status
        self.body = body


@dataclass(frozen=True, slots=True)
class ConsoleResult:
    """One console command line's output lines, or its error message."""

    lines: list[str]
    error: str | None


def _name(text: str) -> str:
    return quote(text, safe="")


class EventStream:
    """The events of one subscription, oldest first; ``close()`` (or ``with``) leaves."""

    def __init__(self, socket: ClientConnection, timeout_s: float | None) -> None:
        self._socket = socket.__enter__()  # websockets wants its connection entered
        self._timeout_s = timeout_s
        self._closed = False
        self._batch: deque[dict[str, Any]] = deque()  # the rest of the last message

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return self

    def __next__(self) -> dict[str, Any]:
        from websockets.exceptions import ConnectionClosed

        while not self._batch:
            try:
                message = self._socket.recv(timeout=self._timeout_s)
            except (TimeoutError, ConnectionClosed):
                self.close()
                raise StopIteration from None
            items = json.loads(message)  # a batch (the stream is asked for batches)
            batch = items if isinstance(items, list) else [items]
            self._batch.extend(dict(item) for item in batch)
        return self._batch.popleft()

    def __enter__(self) -> EventStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._socket.__exit__(None, None, None)


class Client:
    """A synchronous client of one plant's control API."""

    def __init__(
        self, url: str, *, token: str | None = None, timeout_s: float = DEFAULT_TIMEOUT_S
    ) -> None:
        self.url = url.rstrip("/")
        self.token = token
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self._http = httpx.Client(base_url=self.url, headers=headers, timeout=timeout_s)

    def __enter__(self) -> Client:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    def request(self, method: str, path: str, body: object = None, **kw: Any) -> Any:
        """One request; one that changes the plant always sends a JSON body (``{}`` when
        there is no value: the API refuses a request without, as a web form sends it)."""
        if body is None and method.upper() in ("POST", "PUT", "DELETE", "PATCH"):
            body = {}
        try:
            reply = self._http.request(method, path, json=body, **kw)
        except httpx.HTTPError as exc:
            raise ControlError(0, f"{self.url}: cannot reach the control API ({exc})") from None
        try:
            data = reply.json()
        except ValueError:
            data = reply.text
        if reply.status_code >= 400:
            message = data.get("error") if isinstance(data, dict) else None
            raise ControlError(reply.status_code, str(message or data), data)
        return data

    def _answer(self, model: type[BaseModel], method: str, path: str, *a: Any, **kw: Any) -> Any:
        """One request, its answer parsed by ``model`` (502 if it does not fit)."""
        data = self.request(method, path, *a, **kw)
        try:
            model.model_validate(data)
        except ValidationError as exc:
            raise ControlError(
                502, f"{method} {path}: an answer that does not fit ({exc})", data
            ) from None
        return data

    def _answers(self, model: type[BaseModel], path: str) -> list[Any]:
        """A GET answering a list, each item parsed by ``model``."""
        data = self.request("GET", path)
        try:
            _LISTS[model].validate_python(data)
        except ValidationError as exc:
            raise ControlError(
                502, f"GET {path}: an answer that does not fit ({exc})", data
            ) from None
        return list(data)

    # --- the plant and its devices ---------------------------------------------

    def plant(self) -> dict[str, Any]:
        return dict(self._answer(replies.PlantJson, "GET", "/plant"))

    def devices(self) -> list[dict[str, Any]]:
        return list(self.plant()["devices"])

    def status(self, device: str) -> dict[str, Any]:
        return dict(self._answer(replies.StatusJson, "GET", f"/devices/{_name(device)}"))

    def leds(self, device: str) -> dict[str, str]:
        return dict(self._answer(replies.Leds, "GET", f"/devices/{_name(device)}/leds"))

    def inputs(self, device: str) -> list[dict[str, Any]]:
        return self._answers(replies.InputJson, f"/devices/{_name(device)}/inputs")

    def set_input(self, device: str, name: str, value: bool | float | str) -> dict[str, Any]:
        path = f"/devices/{_name(device)}/inputs/{_name(name)}"
        return dict(self._answer(replies.InputSet, "PUT", path, {"value": value}))

    def drive(self, device: str, name: str, signal: Mapping[str, object]) -> dict[str, Any]:
        """Drive an input by a signal table, as the plant file writes it."""
        path = f"/devices/{_name(device)}/inputs/{_name(name)}"
        return dict(self._answer(replies.InputSet, "PUT", path, {"signal": dict(signal)}))

    def faults(self, device: str) -> list[dict[str, Any]]:
        """Each fault that applies, with ``active`` and the ``params`` it is in force with."""
        return self._answers(replies.FaultJson, f"/devices/{_name(device)}/faults")

    def outputs(self, device: str) -> list[dict[str, Any]]:
        """Each output the device drives: ``value`` in its ``unit``, the ``raw`` word beside."""
        return self._answers(replies.OutputJson, f"/devices/{_name(device)}/outputs")

    def set_fault(
        self, device: str, name: str, active: bool = True, **params: float
    ) -> dict[str, Any]:
        path = f"/devices/{_name(device)}/faults/{_name(name)}"
        return dict(
            self._answer(replies.FaultSet, "PUT", path, {"active": active, "params": params})
        )

    def clear_fault(self, device: str, name: str) -> dict[str, Any]:
        return dict(
            self._answer(
                replies.FaultSet, "DELETE", f"/devices/{_name(device)}/faults/{_name(name)}"
            )
        )

    def objects(self, device: str) -> list[str]:
        return list(self.request("GET", f"/devices/{_name(device)}/objects"))

    def read(self, device: str, name: str) -> int:
        """A master's read (a TES's memorized inputs are restored by it)."""
        reply = self._answer(
            replies.ObjectValue, "GET", f"/devices/{_name(device)}/objects/{_name(name)}"
        )
        return int(reply["value"])

    def peek(self, device: str, name: str) -> int:
        path = f"/devices/{_name(device)}/objects/{_name(name)}"
        return int(self._answer(replies.ObjectValue, "GET", path, params={"peek": "true"})["value"])

    def write(self, device: str, name: str, value: int) -> int:
        path = f"/devices/{_name(device)}/objects/{_name(name)}"
        return int(self._answer(replies.ObjectValue, "PUT", path, {"value": value})["value"])

    def power_cycle(self, device: str, seconds: float | None = None) -> dict[str, Any]:
        """24 V off and on again; with ``seconds``, on again that many simulated seconds later."""
        path = f"/devices/{_name(device)}/power-cycle"
        if not seconds:
            return dict(self._answer(replies.PowerCycled, "POST", path))
        return dict(self._answer(replies.PowerCycled, "POST", path, {"seconds": seconds}))

    # --- the PLC -------------------------------------------------------------------

    def start_exchange(
        self,
        m: int,
        c: int,
        send: Sequence[int] = (),
        *,
        text: str | None = None,
        length: int | None = None,
        recv: int = 0,
        txt: int = 0,
    ) -> dict[str, Any]:
        body: dict[str, object] = {"m": m, "c": c, "send": list(send), "recv": recv, "txt": txt}
        if text is not None:
            body["text"] = text
        if length is not None:
            body["length"] = length
        return dict(self._answer(replies.ExchangeJson, "POST", "/exchanges", body))

    def exchange(self, ident: int) -> dict[str, Any]:
        return dict(self._answer(replies.ExchangeJson, "GET", f"/exchanges/{ident}"))

    def wait_exchange(self, ident: int, timeout_s: float = 30.0) -> dict[str, Any]:
        """Poll until the exchange is done (bounded by ``timeout_s`` wall seconds)."""
        deadline = time.monotonic() + timeout_s
        while True:
            state = self.exchange(ident)
            if state["done"]:
                return state
            if time.monotonic() > deadline:
                raise ControlError(0, f"exchange {ident} not done after {timeout_s:g} s", state)
            time.sleep(0.02)

    def power_break(
        self, seconds: float, *, wait: bool = True, wait_s: float = DEFAULT_MODE_WAIT_S
    ) -> dict[str, Any]:
        """Cut the PLC supply for ``seconds`` (simulated); with ``wait``, answered when the
        power is back (at most ``wait_s`` wall seconds), else at once (a runner mode)."""
        return self._mode("/plc/power-break", {"seconds": seconds}, wait, wait_s)

    def remove(self, module: str) -> dict[str, Any]:
        return dict(self._answer(replies.ModuleJson, "POST", "/plc/remove", {"module": module}))

    def insert(self, module: str) -> dict[str, Any]:
        return dict(self._answer(replies.ModuleJson, "POST", "/plc/insert", {"module": module}))

    # --- the clock -----------------------------------------------------------------

    def clock(self) -> dict[str, Any]:
        return dict(self._answer(replies.ClockJson, "GET", "/clock"))

    def pause(self) -> dict[str, Any]:
        return dict(self._answer(replies.ClockEvent, "POST", "/clock/pause"))

    def resume(self) -> dict[str, Any]:
        return dict(self._answer(replies.ClockEvent, "POST", "/clock/resume"))

    def step(
        self, ms: float, *, wait: bool = True, wait_s: float = DEFAULT_MODE_WAIT_S
    ) -> dict[str, Any]:
        """Run simulated time by ``ms``, paused or not; with ``wait`` the answer comes at
        the step's end (at most ``wait_s`` wall seconds), else at once (docs/control.md)."""
        return self._mode("/clock/step", {"ms": ms}, wait, wait_s)

    def run_until(
        self, t_s: float, *, wait: bool = True, wait_s: float = DEFAULT_MODE_WAIT_S
    ) -> dict[str, Any]:
        """Run simulated time until ``t_s``; ``wait`` as for ``step``."""
        return self._mode("/clock/run-until", {"t_s": t_s}, wait, wait_s)

    def _mode(self, path: str, body: dict[str, Any], wait: bool, wait_s: float) -> dict[str, Any]:
        body = {**body, "wait": wait, "wait_s": wait_s} if wait else body
        timeout = wait_s + DEFAULT_TIMEOUT_S if wait else None
        extra: dict[str, Any] = {} if timeout is None else {"timeout": timeout}
        return dict(self._answer(replies.ClockEvent, "POST", path, body, **extra))

    def set_speed(self, speed: float | str) -> dict[str, Any]:
        return dict(self._answer(replies.ClockEvent, "PUT", "/clock/speed", {"speed": speed}))

    # --- the console and the events ------------------------------------------------------

    def console(self, line: str, wait_s: float = 60.0, *, text: str | None = None) -> ConsoleResult:
        """One console line; ``text`` comes with it (a program's, for ``prog load -``)."""
        body: dict[str, object] = {"line": line, "wait_s": wait_s}
        if text is not None:
            body["text"] = text
        reply = self._answer(replies.ConsoleAnswer, "POST", "/console", body, timeout=wait_s + 5)
        return ConsoleResult(list(reply["lines"]), reply["error"])

    def events(
        self,
        kinds: Sequence[str] = (),
        devices: Sequence[str] = (),
        *,
        queue: int | None = None,
        timeout_s: float | None = None,
    ) -> EventStream:
        """The event stream (a WebSocket, subscribed before this returns); the iterator
        ends after ``timeout_s`` without an event, or when the plant closes it."""
        from websockets.exceptions import InvalidHandshake
        from websockets.sync.client import connect

        query: dict[str, str] = {"batch": "1"}
        if kinds:
            query["kind"] = ",".join(kinds)
        if devices:
            query["device"] = ",".join(devices)
        if queue is not None:
            query["queue"] = str(queue)
        if self.token:
            query["token"] = self.token
        parts = urlsplit(self.url)
        scheme = "wss" if parts.scheme == "https" else "ws"
        url = f"{scheme}://{parts.netloc}{parts.path}/events"
        if query:
            url += "?" + urlencode(query)
        try:
            opened = connect(url, open_timeout=10)
        except (InvalidHandshake, OSError, TimeoutError) as exc:
            raise ControlError(0, f"{self.url}: the event stream refused ({exc})") from None

        return EventStream(opened, timeout_s)


_LISTS: dict[type[BaseModel], TypeAdapter[list[Any]]] = {
    model: TypeAdapter(list[model])  # type: ignore[valid-type]
    for model in (replies.InputJson, replies.FaultJson, replies.OutputJson)
}

__all__ = ["Client", "ConsoleResult", "ControlError", "EventStream"]
