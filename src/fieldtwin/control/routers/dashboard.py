"""``/dashboard/state``: the whole plant as the dashboard draws it (docs/dashboard.md);
the page and its files are fieldtwin.control.dashboard's."""

from __future__ import annotations

from fastapi import APIRouter

from fieldtwin.control.panels import panels
from fieldtwin.control.replies import DashboardState
from fieldtwin.control.routers.common import REPLY, Hop


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(tags=["dashboard"])

    @api.get("/dashboard/state", summary="the whole plant as the dashboard draws it", **REPLY)
    async def state() -> DashboardState:
        return DashboardState.model_validate(await hop.read("dashboard", lambda: panels(c)))

    return api


__all__ = ["router"]
