"""``/plant``: the plant, its clock and its devices."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.replies import PlantJson
from fieldtwin.control.routers.common import REPLY, Hop


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(tags=["plant"])

    @api.get("/plant", summary="the plant, its clock and its devices", **REPLY)
    async def plant() -> PlantJson:
        return PlantJson.model_validate(await hop.read("plant", c.plant_json))

    return api


__all__ = ["router"]
