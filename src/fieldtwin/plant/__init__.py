"""A plant file (TOML) -> a PLC with its modules, TES terminals, signals and endpoints.

Fixed keys (tests outside the project rely on them)::

    [plc]
    model = "TSX 87"
    scan_ms = 10

    [[module]]
    type = "TSX AEM 811"
    rack = 0
    slot = 5

    [[tes]]
    model = "TES 32EST"
    slave = 1
    endpoint = "tcp://127.0.0.1:5020"

Three steps, three modules: reading (``read_plant``, ``describe``: the TOML
checked against the kinds' schemas, fieldtwin.plant.reading), building
(``build_plant``: the PLC and the devices, nothing opened,
fieldtwin.plant.building) and the value they give (``Plant``,
fieldtwin.plant.value), whose ports the runtime's binder opens afterwards
(fieldtwin.plant.ports): ``load_plant`` binds the module ports (SCM channels),
``fieldtwin run`` (fieldtwin.session) binds every port.  Errors name the file
and the field path: ``plant.toml: module[1].slot: ...``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from fieldtwin.clock import SimClock
from fieldtwin.plant.building import FROM_PLANT, KIND_PLC, build_plant
from fieldtwin.plant.ports import Ports
from fieldtwin.plant.reading import (
    DEFAULT_NAME,
    DEFAULT_PLANT,
    MAX_EMBEDDED_BYTES,
    MAX_PLANT_BYTES,
    PROGRAM_KEYS,
    TOP_LEVEL,
    DeviceDescription,
    PlantDescription,
    PlantFile,
    PlcDescription,
    describe,
    embedded_plant,
    parse,
    plant_speed,
    read_plant,
    recording_header,
)
from fieldtwin.plant.value import Plant
from fieldtwin.runtime.binder import SERIAL_LINE

if TYPE_CHECKING:
    from fieldtwin.runtime.runner import Runner

_parse = parse  # the name tests of earlier releases import


def load_plant(
    path: str | Path | None = None,
    *,
    clock: SimClock | None = None,
    runner: Runner | None = None,
    speed: float | str | None = FROM_PLANT,
) -> Plant:
    """Read and build a plant, and open its module ports (SCM channels) through the binder.

    The TES Modbus endpoints stay closed until ``plant.start_endpoints(runner)``:
    the console and Python are the TES's master themselves.
    """
    plant = build_plant(read_plant(path), clock=clock, runner=runner, speed=speed)
    try:
        plant.ports.bind(plant.devices, runner, (SERIAL_LINE,), plant.events)
    except BaseException:
        plant.close()
        raise
    return plant


__all__ = [
    "DEFAULT_NAME",
    "DEFAULT_PLANT",
    "FROM_PLANT",
    "KIND_PLC",
    "MAX_EMBEDDED_BYTES",
    "MAX_PLANT_BYTES",
    "PROGRAM_KEYS",
    "TOP_LEVEL",
    "DeviceDescription",
    "Plant",
    "PlantDescription",
    "PlantFile",
    "PlcDescription",
    "Ports",
    "build_plant",
    "describe",
    "embedded_plant",
    "load_plant",
    "parse",
    "plant_speed",
    "read_plant",
    "recording_header",
]
