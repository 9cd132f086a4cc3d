"""``/devices/{ident}``: a device's status, LEDs, inputs, outputs, and a TES's power cycle."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.lane import LaneRoute
from fieldtwin.control.replies import InputJson, InputSet, Leds, OutputJson, PowerCycled, StatusJson
from fieldtwin.control.routers.common import REPLY, Hop
from fieldtwin.control.schemas import InputBody, PowerCycleBody

# set an input: the route below and the fast lane in front of the router (control/lane.py)
SET_INPUT: LaneRoute[InputBody, InputSet] = LaneRoute(
    "PUT",
    "/devices/{ident}/inputs/{name}",
    InputBody,
    lambda at, body: ("set_input", (at["ident"], at["name"], body.value, body.signal)),
    InputSet,
)


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(prefix="/devices/{ident}", tags=["devices"])

    @api.get(
        "",
        summary="a device's status: state, mode, LEDs, ports, active faults, outputs",
        **REPLY,
    )
    async def status(ident: str) -> StatusJson:
        return StatusJson.model_validate(await hop.read(("status", ident), lambda: c.status(ident)))

    @api.get("/leds", summary="a device's front-panel LEDs", **REPLY)
    async def leds(ident: str) -> Leds:
        return Leds.model_validate(await hop.read(("leds", ident), lambda: c.leds(ident)))

    @api.get("/inputs", summary="a device's inputs", **REPLY)
    async def inputs(ident: str) -> list[InputJson]:
        found = await hop.read(("inputs", ident), lambda: c.inputs(ident))
        return [InputJson.model_validate(one) for one in found]

    @api.put("/inputs/{name}", summary="set an input, or drive it by a signal", **REPLY)
    async def set_input(ident: str, name: str, body: InputBody) -> InputSet:
        command, args = SET_INPUT.call({"ident": ident, "name": name}, body)
        return SET_INPUT.answer(await hop.do(command, *args))

    @api.get(
        "/outputs",
        summary="every output a device drives, in its units, the raw word beside",
        responses={404: {"description": "no such device (the message lists the devices)"}},
        **REPLY,
    )
    async def outputs(ident: str) -> list[OutputJson]:
        found = await hop.read(("outputs", ident), lambda: c.outputs(ident))
        return [OutputJson.model_validate(one) for one in found]

    @api.post(
        "/power-cycle",
        summary="a TES: 24 V off and on again, at once or after an outage of some seconds",
        responses={409: {"description": "an outage of this TES is in progress"}},
        **REPLY,
    )
    async def power_cycle(ident: str, body: PowerCycleBody | None = None) -> PowerCycled:
        if body is None or not body.seconds:
            return PowerCycled.model_validate(await hop.do("power_cycle", ident))
        return PowerCycled.model_validate(await hop.do("power_cycle", ident, body.seconds))

    return api


__all__ = ["SET_INPUT", "router"]
