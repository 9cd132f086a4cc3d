"""``/exchanges`` and ``/plc``: Text Block exchanges, the PLC's power, its slots."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.replies import ClockEvent, ExchangeJson, ModuleJson
from fieldtwin.control.routers.common import REPLY, Hop, mode
from fieldtwin.control.schemas import ExchangeBody, ModuleBody, PowerBreakBody


def router(hop: Hop) -> APIRouter:
    api = APIRouter(tags=["plc"])

    @api.post("/exchanges", status_code=202, summary="start a Text Block exchange", **REPLY)
    async def start(body: ExchangeBody) -> ExchangeJson:
        started = await hop.do(
            "start_exchange", body.m, body.c, body.send, body.text, body.length, body.recv, body.txt
        )
        return ExchangeJson.model_validate(started)

    @api.get("/exchanges/{ident}", summary="an exchange: state, and its result once done", **REPLY)
    async def poll(ident: int) -> ExchangeJson:
        return ExchangeJson.model_validate(await hop.do("exchange", ident))

    @api.post("/plc/power-break", summary="cut the PLC supply for some seconds (a mode)", **REPLY)
    async def power_break(body: PowerBreakBody) -> ClockEvent:
        state = await mode(hop, ("power_break", body.seconds), body.wait, body.wait_s)
        return ClockEvent.model_validate(state)

    @api.post("/plc/remove", summary="pull a module out of its slot under power", **REPLY)
    async def remove(body: ModuleBody) -> ModuleJson:
        return ModuleJson.model_validate(await hop.do("remove", body.module))

    @api.post("/plc/insert", summary="put a module back (it runs its self-test)", **REPLY)
    async def insert(body: ModuleBody) -> ModuleJson:
        return ModuleJson.model_validate(await hop.do("insert", body.module))

    return api


__all__ = ["router"]
