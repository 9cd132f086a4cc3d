"""``/console``: one console command line on the running plant (docs/control.md)."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.console import with_text
from fieldtwin.control.replies import ConsoleAnswer
from fieldtwin.control.routers.common import REPLY, Hop, mode_end
from fieldtwin.control.schemas import ConsoleBody
from fieldtwin.errors import FieldtwinError
from fieldtwin.runtime.inbox import InboxClosed, InboxFull


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(tags=["console"])

    @api.post("/console", summary="run one console command line on the running plant", **REPLY)
    async def console(body: ConsoleBody) -> ConsoleAnswer:
        # an advance or power break starts a runner mode: answered at its end (at most
        # wait_s), the plant serving every other request meanwhile
        # the line is a value through the plant's door, as every command
        try:
            answer, ended = await hop.sim.line(
                with_text(body.line, body.text),
                then=lambda lines: ({"lines": lines, "error": None}, c.take_console_mode()),
                wait_s=body.wait_s + 1,
            )
        except (InboxFull, InboxClosed):
            raise  # the simulation's door is full or shut: 503, as for every command
        except FieldtwinError as exc:  # the console's own refusal: its answer, not a 400
            await hop.run(c.take_console_mode)  # a refused line leaves no mode to wait for
            return ConsoleAnswer.model_validate({"lines": [], "error": str(exc)})
        if ended is not None:
            result = await mode_end(c, ended, body.wait_s)
            if result is not None:
                answer = await hop.run(lambda: c.console_mode_answer(result))
        return ConsoleAnswer.model_validate(answer)

    return api


__all__ = ["router"]
