"""The control API's routes (FastAPI): REST/JSON over the Device face (docs/control.md).

Each handler validates its request (the schemas), hands one function to the
simulation's thread (``Sim.call``) and answers with its result.  Errors are
JSON: ``{"error": "...", "field": "...", "allowed": "..."}``; 400 for a user's
mistake the plant names, 404 for an unknown device, input, fault or exchange,
409 for a request the plant's state refuses (a time already past, a busy Text
Block), 413 for a body over 64 KiB, 422 for a body that does not fit its schema,
503 while the simulation cannot take a command, 504 when it did not answer in time.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Future
from typing import Any, TypeVar

from fastapi import FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.cors import CORSMiddleware

from fieldtwin import __version__
from fieldtwin.console import with_text
from fieldtwin.control.dashboard import add_dashboard, add_docs
from fieldtwin.control.document import allowed_methods, bodyless, declare, routed
from fieldtwin.control.guards import BodyLimit, BrowserGate, TokenGate, origin_of
from fieldtwin.control.resources import Conflict, Control, NotFound
from fieldtwin.control.schemas import (
    ConsoleBody,
    ExchangeBody,
    FaultBody,
    InputBody,
    ModeBody,
    ModuleBody,
    ObjectBody,
    PowerBreakBody,
    RunUntilBody,
    SpeedBody,
    StepBody,
)
from fieldtwin.control.sim import DEFAULT_WAIT_S, CommandTimeout, Sim
from fieldtwin.control.stream import add_stream
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.runtime.inbox import InboxClosed, InboxFull

T = TypeVar("T")
MODE_POLL_S = 0.25  # a request waiting for a mode's end looks this often for a stopped run


_TYPE_TAGS = {"bool", "int", "float", "str", "list", "dict", "none"}


def _field(loc: Sequence[object]) -> str:
    """``body.speed`` from pydantic's loc (a union's member tags left out)."""
    parts = [
        str(part)
        for part in loc
        if isinstance(part, int) or (str(part).isidentifier() and str(part) not in _TYPE_TAGS)
    ]
    return ".".join(parts) or "body"


# what a field allows, by the kind of error pydantic found (its ``ctx`` gives bounds)
_ALLOWS: dict[str, Callable[[dict[str, Any]], str]] = {
    "float_type": lambda ctx: "a number",
    "float_parsing": lambda ctx: "a number",
    "finite_number": lambda ctx: "a finite number",
    "int_type": lambda ctx: "a whole number",
    "int_from_float": lambda ctx: "a whole number",
    "int_parsing": lambda ctx: "a whole number",
    "bool_type": lambda ctx: "true or false",
    "string_type": lambda ctx: "a string",
    "dict_type": lambda ctx: "a JSON object",
    "model_type": lambda ctx: "a JSON object",
    "model_attributes_type": lambda ctx: "a JSON object",
    "list_type": lambda ctx: "a list",
    "literal_error": lambda ctx: str(ctx.get("expected", "")),
    "greater_than": lambda ctx: f"a value > {ctx.get('gt')}",
    "greater_than_equal": lambda ctx: f"a value >= {ctx.get('ge')}",
    "less_than": lambda ctx: f"a value < {ctx.get('lt')}",
    "less_than_equal": lambda ctx: f"a value <= {ctx.get('le')}",
    "string_too_long": lambda ctx: f"at most {ctx.get('max_length')} characters",
    "string_too_short": lambda ctx: f"at least {ctx.get('min_length')} characters",
    "too_long": lambda ctx: f"at most {ctx.get('max_length')} items",
    "too_short": lambda ctx: f"at least {ctx.get('min_length')} items",
    "missing": lambda ctx: "a value (the field is required)",
    "extra_forbidden": lambda ctx: "no such field (GET /openapi.json lists the route's fields)",
    "json_invalid": lambda ctx: "a JSON body",
}


def _allows(error: Mapping[str, Any]) -> str:
    """What the field allows, said plainly; pydantic's own words where it has no phrase."""
    phrase = _ALLOWS.get(str(error.get("type", "")))
    ctx = error.get("ctx")
    if phrase is not None:
        return phrase(ctx if isinstance(ctx, dict) else {})
    said = str(ctx["error"]) if isinstance(ctx, dict) and "error" in ctx else str(error["msg"])
    return said.removeprefix("Value error, ").removeprefix("Input should be ")


def _refused(field: str, error: Mapping[str, Any]) -> str:
    """What was wrong: the value refused (shortened), or the field missing."""
    if error.get("type") == "missing":
        return f"{field}: required"
    if "input" not in error:
        return f"{field}: {error.get('msg', 'invalid')}"
    shown = json.dumps(error["input"], default=str)
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return f"{field}: {shown} is not allowed"


def _validation(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, RequestValidationError)
    problems: dict[str, list[str]] = {}
    allows: dict[str, list[str]] = {}
    first: dict[str, str] = {}
    for error in exc.errors()[:20]:
        where = _field(error.get("loc", ()))
        problems.setdefault(where, []).append(str(error.get("msg", "")))
        allows.setdefault(where, []).append(_allows(error))
        first.setdefault(where, _refused(where, error))
    field = next(iter(problems), "body")
    allowed = " or ".join(dict.fromkeys(allows.get(field, ["a valid body"])))
    return JSONResponse(
        status_code=422,
        content={
            "error": first.get(field, f"{field}: invalid"),
            "field": field,
            "allowed": allowed,
            "problems": [{"field": f, "problem": " or ".join(t)} for f, t in problems.items()],
        },
    )


def _http_error(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, StarletteHTTPException)
    body = {"error": str(exc.detail)}
    if "body" in str(exc.detail):
        body["field"] = "body"
    headers = exc.headers
    if exc.status_code == 405:  # every method of the path, not only the first route's
        allow = ", ".join(allowed_methods(request.app, request.scope))
        body["allowed"] = allow
        headers = {**(headers or {}), "Allow": allow}
    return JSONResponse(status_code=exc.status_code, content=body, headers=headers)


def _plant_error(request: Request, exc: Exception) -> JSONResponse:
    status = 404 if isinstance(exc, NotFound) else 409 if isinstance(exc, Conflict) else 400
    return JSONResponse(status_code=status, content={"error": str(exc)})


def _busy(request: Request, exc: Exception) -> JSONResponse:
    return JSONResponse(status_code=503, content={"error": str(exc)})


def _late(request: Request, exc: Exception) -> JSONResponse:
    return JSONResponse(status_code=504, content={"error": str(exc)})


def create_app(
    control: Control,
    sim: Sim,
    *,
    token: str | None = None,
    host: str | None = None,
    allow_origins: Sequence[str] = (),
) -> Any:
    """The ASGI application: the routes inside the token gate, the browser's doors
    (Host, Origin, JSON bodies: ``host`` is the configured listening host) and the
    body limit (fieldtwin.control.guards)."""
    app = FastAPI(
        docs_url=None,
        redoc_url=None,
        title="fieldtwin control API",
        version=__version__,
        description="A running fieldtwin plant: devices, inputs, faults, objects, Text Blocks,"
        " power, the clock, the console and the event stream (docs/control.md).",
    )
    app.add_exception_handler(RequestValidationError, _validation)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(ConfigError, _plant_error)
    app.add_exception_handler(InboxFull, _busy)
    app.add_exception_handler(InboxClosed, _busy)
    app.add_exception_handler(CommandTimeout, _late)

    async def run(fn: Callable[[], T], wait_s: float = DEFAULT_WAIT_S) -> T:
        return await sim.call(fn, wait_s)

    _plant_routes(app, control, run, sim)
    _device_routes(app, control, run, sim.command)
    _plc_routes(app, control, run, sim.command)
    _clock_routes(app, control, run, sim.command)
    add_stream(app, control, sim)
    add_dashboard(app, control, run)
    add_docs(app)
    declare(app, token=token is not None)
    inner: Any = TokenGate(app, token)
    origins = [o for o in map(origin_of, allow_origins) if o]
    if origins:  # a page of an allowed origin may call the API (its preflights answered)
        inner = CORSMiddleware(
            inner,
            allow_origins=origins,
            allow_methods=["GET", "POST", "PUT", "DELETE"],
            allow_headers=["authorization", "content-type"],
        )
    doors = BrowserGate(
        inner, host=host, allow_origins=origins, bodyless=bodyless(app), routed=routed(app)
    )
    return BodyLimit(doors)


Run = Callable[..., Any]
Do = Callable[..., Any]  # Sim.command: a control command, a value through the plant's door


def _plant_routes(app: FastAPI, c: Control, run: Run, sim: Sim) -> None:
    @app.get("/plant", summary="the plant, its clock and its devices")
    async def plant() -> Any:
        return await run(c.plant_json)

    @app.post("/console", summary="run one console command line on the running plant")
    async def console(body: ConsoleBody) -> Any:
        # an advance or power break starts a runner mode: answered at its end (at most
        # wait_s), the plant serving every other request meanwhile
        # the line is a value through the plant's door, as every command
        try:
            answer, ended = await sim.line(
                with_text(body.line, body.text),
                then=lambda lines: ({"lines": lines, "error": None}, c.take_console_mode()),
                wait_s=body.wait_s + 1,
            )
        except (InboxFull, InboxClosed):
            raise  # the simulation's door is full or shut: 503, as for every command
        except FieldtwinError as exc:  # the console's own refusal: its answer, not a 400
            await run(c.take_console_mode)  # a refused line leaves no mode to wait for
            return {"lines": [], "error": str(exc)}
        if ended is None:
            return answer
        result = await _mode_end(c, ended, body.wait_s)
        return answer if result is None else await run(lambda: c.console_mode_answer(result))


def _device_routes(app: FastAPI, c: Control, run: Run, do: Do) -> None:
    @app.get(
        "/devices/{ident}",
        summary="a device's status: state, mode, LEDs, ports, active faults, outputs",
    )
    async def status(ident: str) -> Any:
        return await run(lambda: c.status(ident))

    @app.get("/devices/{ident}/leds", summary="a device's front-panel LEDs")
    async def leds(ident: str) -> Any:
        return await run(lambda: c.leds(ident))

    @app.get("/devices/{ident}/inputs", summary="a device's inputs")
    async def inputs(ident: str) -> Any:
        return await run(lambda: c.inputs(ident))

    @app.put("/devices/{ident}/inputs/{name}", summary="set an input, or drive it by a signal")
    async def set_input(ident: str, name: str, body: InputBody) -> Any:
        return await do("set_input", ident, name, body.value, body.signal)

    @app.get(
        "/devices/{ident}/faults",
        summary="the faults that apply to a device, each active or not, with its parameters",
    )
    async def faults(ident: str) -> Any:
        return await run(lambda: c.faults(ident))

    @app.put("/devices/{ident}/faults/{name}", summary="set (or clear) a fault")
    async def set_fault(ident: str, name: str, body: FaultBody) -> Any:
        return await do("set_fault", ident, name, body.active, body.params)

    @app.delete("/devices/{ident}/faults/{name}", summary="clear a fault")
    async def clear_fault(ident: str, name: str) -> Any:
        return await do("set_fault", ident, name, False, {})

    @app.get(
        "/devices/{ident}/outputs",
        summary="every output a device drives, in its units, the raw word beside",
        responses={404: {"description": "no such device (the message lists the devices)"}},
    )
    async def outputs(ident: str) -> Any:
        return await run(lambda: c.outputs(ident))

    @app.get("/devices/{ident}/objects", summary="the objects a master reads and writes")
    async def objects(ident: str) -> Any:
        return await run(lambda: c.objects(ident))

    @app.get("/devices/{ident}/objects/{name}", summary="read an object (peek: no side effect)")
    async def read_object(ident: str, name: str, peek: bool = Query(False)) -> Any:
        return await do("read_object", ident, name, peek)

    @app.put("/devices/{ident}/objects/{name}", summary="write an object")
    async def write_object(ident: str, name: str, body: ObjectBody) -> Any:
        return await do("write_object", ident, name, body.value)

    @app.post("/devices/{ident}/power-cycle", summary="a TES: 24 V off and on again")
    async def power_cycle(ident: str) -> Any:
        return await do("power_cycle", ident)


def _plc_routes(app: FastAPI, c: Control, run: Run, do: Do) -> None:
    @app.post("/exchanges", status_code=202, summary="start a Text Block exchange")
    async def start(body: ExchangeBody) -> Any:
        return await do(
            "start_exchange", body.m, body.c, body.send, body.text, body.length, body.recv, body.txt
        )

    @app.get("/exchanges/{ident}", summary="an exchange: state, and its result once done")
    async def poll(ident: int) -> Any:
        return await do("exchange", ident)

    @app.post("/plc/power-break", summary="cut the PLC supply for some seconds (a mode)")
    async def power_break(body: PowerBreakBody) -> Any:
        return await _mode(run, do, c, ("power_break", body.seconds), body)

    @app.post("/plc/remove", summary="pull a module out of its slot under power")
    async def remove(body: ModuleBody) -> Any:
        return await do("remove", body.module)

    @app.post("/plc/insert", summary="put a module back (it runs its self-test)")
    async def insert(body: ModuleBody) -> Any:
        return await do("insert", body.module)


async def _mode(run: Run, do: Do, c: Control, start: tuple[str, float], body: ModeBody) -> Any:
    """Start a runner mode (step, run-until, power-break); its state at once, or with
    ``wait`` at its end (at most ``wait_s``; the run stopping ends the wait too)."""
    state, ended = await do(*start, then=lambda state: (state, c.mode_ended))
    if not body.wait or ended is None:
        return state
    result = await _mode_end(c, ended, body.wait_s)
    if result is not None:
        return result
    return await run(c.clock_state)  # still running: the mode as it stands


async def _mode_end(c: Control, ended: Future[Any], wait_s: float) -> Any | None:
    """The end of a mode (its clock state), awaited at most ``wait_s``; None if it
    has not ended by then or the run stops."""
    done = asyncio.wrap_future(ended)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + wait_s
    try:
        while not done.done() and c.runner.running and loop.time() < deadline:
            await asyncio.wait({done}, timeout=min(MODE_POLL_S, deadline - loop.time()))
        ended_now = done.done() and not done.cancelled()
    finally:
        if not done.done():
            done.cancel()  # the mode's own future runs on (it cannot be cancelled)
    return done.result() if ended_now else None


def _clock_routes(app: FastAPI, c: Control, run: Run, do: Do) -> None:
    @app.get("/clock", summary="simulated time, paused or not, speed")
    async def clock() -> Any:
        return await run(c.clock_json)

    @app.post("/clock/pause", summary="hold simulated time")
    async def pause() -> Any:
        return await do("pause")

    @app.post("/clock/resume", summary="let simulated time run again")
    async def resume() -> Any:
        return await do("resume")

    @app.post("/clock/step", summary="run simulated time by ms, paused or not (a mode)")
    async def step(body: StepBody) -> Any:
        return await _mode(run, do, c, ("step", body.ms), body)

    @app.post("/clock/run-until", summary="run simulated time until t_s (a mode)")
    async def run_until(body: RunUntilBody) -> Any:
        return await _mode(run, do, c, ("run_until", body.t_s), body)

    @app.put("/clock/speed", summary="change the speed factor (or max)")
    async def speed(body: SpeedBody) -> Any:
        value = None if body.speed == "max" else float(body.speed)
        return await do("set_speed", value)


__all__ = ["create_app"]
