"""The control API's routes, one APIRouter per resource group (docs/control.md).

Each module's ``router(control, sim)`` gives its group's routes: the request bodies
are the models of fieldtwin.control.schemas, the answers those of
fieldtwin.control.replies (the OpenAPI document and ``fieldtwin.client`` use the
same).  A command is one function handed to the simulation's thread
(:class:`Hop`); a read that changes nothing is answered from the snapshot the
simulation published (:mod:`fieldtwin.control.snapshot`).
"""

from fieldtwin.control.routers import (
    clock,
    console,
    dashboard,
    devices,
    faults,
    objects,
    plant,
    plc,
    scenarios,
    tags,
)

GROUPS = (plant, clock, devices, faults, objects, plc, scenarios, console, dashboard, tags)
# the hot routes the fast lane answers on their happy path (fieldtwin.control.lane): two
# commands, and the clock read from the snapshot
LANE = (devices.SET_INPUT, objects.WRITE_OBJECT, clock.CLOCK)

__all__ = ["GROUPS", "LANE"]
