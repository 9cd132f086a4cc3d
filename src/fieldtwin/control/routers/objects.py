"""``/devices/{ident}/objects``: the objects a master reads and writes."""

from __future__ import annotations

from fastapi import APIRouter, Query

from fieldtwin.control.lane import LaneRoute
from fieldtwin.control.replies import ObjectValue
from fieldtwin.control.routers.common import REPLY, Hop
from fieldtwin.control.schemas import ObjectBody

# write an object (a PL7 object, a TES register): the route below and the fast lane
# in front of the router (control/lane.py)
WRITE_OBJECT: LaneRoute[ObjectBody, ObjectValue] = LaneRoute(
    "PUT",
    "/devices/{ident}/objects/{name}",
    ObjectBody,
    lambda at, body: ("write_object", (at["ident"], at["name"], body.value)),
    ObjectValue,
)


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(prefix="/devices/{ident}/objects", tags=["objects"])

    @api.get("", summary="the objects a master reads and writes", **REPLY)
    async def objects(ident: str) -> list[str]:
        return list(await hop.read(("objects", ident), lambda: c.objects(ident)))

    @api.get("/{name}", summary="read an object (peek: no side effect)", **REPLY)
    async def read_object(ident: str, name: str, peek: bool = Query(False)) -> ObjectValue:
        if peek:  # changes nothing: from the snapshot
            found = await hop.read(("peek", ident, name), lambda: c.read_object(ident, name, True))
        else:  # a master's read may change the device (a TES's memorized inputs)
            found = await hop.do("read_object", ident, name, False)
        return ObjectValue.model_validate(found)

    @api.put("/{name}", summary="write an object", **REPLY)
    async def write_object(ident: str, name: str, body: ObjectBody) -> ObjectValue:
        command, args = WRITE_OBJECT.call({"ident": ident, "name": name}, body)
        return WRITE_OBJECT.answer(await hop.do(command, *args))

    return api


__all__ = ["WRITE_OBJECT", "router"]
