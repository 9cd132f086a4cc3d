"""``/console``: one console command line on the running plant (docs/control.md)."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.replies import ConsoleAnswer
from fieldtwin.control.routers.common import REPLY, Hop, mode_end
from fieldtwin.control.schemas import ConsoleBody


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(tags=["console"])

    @api.post("/console", summary="run one console command line on the running plant", **REPLY)
    async def console(body: ConsoleBody) -> ConsoleAnswer:
        # an advance or power break starts a runner mode: answered at its end (at most
        # wait_s), the plant serving every other request meanwhile
        answer, ended = await hop.run(
            lambda: (c.console_line(body.line, body.text), c.take_console_mode()),
            body.wait_s + 1,
        )
        if ended is not None:
            result = await mode_end(c, ended, body.wait_s)
            if result is not None:
                answer = await hop.run(lambda: c.console_mode_answer(result))
        return ConsoleAnswer.model_validate(answer)

    return api


__all__ = ["router"]
