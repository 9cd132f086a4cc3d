"""``/scenarios``: start a scenario on the running plant, follow it, read its result
(docs/scenarios.md).  The request carries the scenario's text: no request reads a file."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter
from pydantic import Field

from fieldtwin.control.replies import Reply
from fieldtwin.control.routers.common import REPLY, Hop
from fieldtwin.control.scenarios import ScenarioRuns
from fieldtwin.control.schemas import Closed

# a scenario's text in a request: within the API's body limit (64 KiB: guards.MAX_BODY)
MAX_TEXT = 60_000


class ScenarioBody(Closed):
    """A scenario file's text (TOML, docs/scenarios.md, at most 60000 characters here) and
    the name its errors give."""

    text: Annotated[str, Field(max_length=MAX_TEXT)]
    name: Annotated[str, Field(min_length=1, max_length=128)] = "scenario"


class ScenarioJson(Reply):
    """A scenario: done and passed once it has run; each step's and expectation's outcome."""

    id: int
    name: str
    title: str
    started_s: float
    end_s: float
    done: bool
    passed: bool
    failure: str | None
    outcomes: list[dict[str, object]]


class ScenarioItem(Reply):
    id: int
    name: str
    done: bool
    passed: bool


def router(hop: Hop) -> APIRouter:
    runs = ScenarioRuns(hop.control.plant)
    api = APIRouter(prefix="/scenarios", tags=["scenarios"])

    @api.post(
        "",
        status_code=202,
        summary="start a scenario now (its TOML text)",
        responses={
            409: {
                "description": "not a scenario of this plant (the message names the table and"
                " the field), or too many running"
            },
        },
        **REPLY,
    )
    async def start(body: ScenarioBody) -> ScenarioJson:
        return ScenarioJson.model_validate(await hop.run(lambda: runs.start(body.text, body.name)))

    @api.get("", summary="the scenarios started (the last 64)", **REPLY)
    async def listing() -> list[ScenarioItem]:
        return [ScenarioItem.model_validate(one) for one in await hop.run(runs.list)]

    @api.get(
        "/{ident}",
        summary="a scenario: its outcomes so far, its result once done",
        responses={404: {"description": "no such scenario (the last 64 are kept)"}},
        **REPLY,
    )
    async def status(ident: int) -> ScenarioJson:
        return ScenarioJson.model_validate(await hop.run(lambda: runs.json(ident)))

    return api


__all__ = ["ScenarioBody", "ScenarioJson", "router"]
