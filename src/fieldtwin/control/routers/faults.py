"""``/devices/{ident}/faults``: the faults that apply to a device; set and clear one."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.replies import FaultJson, FaultSet
from fieldtwin.control.routers.common import REPLY, Hop
from fieldtwin.control.schemas import FaultBody


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(prefix="/devices/{ident}/faults", tags=["faults"])

    @api.get(
        "",
        summary="the faults that apply to a device, each active or not, with its parameters",
        **REPLY,
    )
    async def faults(ident: str) -> list[FaultJson]:
        found = await hop.read(("faults", ident), lambda: c.faults(ident))
        return [FaultJson.model_validate(one) for one in found]

    @api.put("/{name}", summary="set (or clear) a fault", **REPLY)
    async def set_fault(ident: str, name: str, body: FaultBody) -> FaultSet:
        done = await hop.do("set_fault", ident, name, body.active, body.params)
        return FaultSet.model_validate(done)

    @api.delete("/{name}", summary="clear a fault", **REPLY)
    async def clear_fault(ident: str, name: str) -> FaultSet:
        return FaultSet.model_validate(await hop.do("set_fault", ident, name, False, {}))

    return api


__all__ = ["router"]
