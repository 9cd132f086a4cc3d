"""``/clock``: simulated time, paused or not, speed, and the runner modes (docs/control.md,
"The clock")."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.lane import LaneRead
from fieldtwin.control.replies import ClockEvent, ClockJson
from fieldtwin.control.routers.common import REPLY, Hop, mode
from fieldtwin.control.schemas import RunUntilBody, SpeedBody, StepBody

# the clock from the snapshot: the route below and the fast lane in front of the router
# (control/lane.py)
CLOCK: LaneRead[ClockJson] = LaneRead("/clock", lambda c, at: ("clock", c.clock_json), ClockJson)


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(prefix="/clock", tags=["clock"])

    @api.get("", summary="simulated time, paused or not, speed", **REPLY)
    async def clock() -> ClockJson:
        return CLOCK.answer(await hop.read(*CLOCK.read(c, {})))

    @api.post("/pause", summary="hold simulated time", **REPLY)
    async def pause() -> ClockEvent:
        return ClockEvent.model_validate(await hop.do("pause"))

    @api.post("/resume", summary="let simulated time run again", **REPLY)
    async def resume() -> ClockEvent:
        return ClockEvent.model_validate(await hop.do("resume"))

    @api.post("/step", summary="run simulated time by ms, paused or not (a mode)", **REPLY)
    async def step(body: StepBody) -> ClockEvent:
        state = await mode(hop, ("step", body.ms), body.wait, body.wait_s)
        return ClockEvent.model_validate(state)

    @api.post("/run-until", summary="run simulated time until t_s (a mode)", **REPLY)
    async def run_until(body: RunUntilBody) -> ClockEvent:
        state = await mode(hop, ("run_until", body.t_s), body.wait, body.wait_s)
        return ClockEvent.model_validate(state)

    @api.put("/speed", summary="change the speed factor (or max)", **REPLY)
    async def speed(body: SpeedBody) -> ClockEvent:
        value = None if body.speed == "max" else float(body.speed)
        return ClockEvent.model_validate(await hop.do("set_speed", value))

    return api


__all__ = ["CLOCK", "router"]
