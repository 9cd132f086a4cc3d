"""A kind of device: its name, family, plant schema and how a plant table builds it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import Device, Family
from fieldtwin.devices.schema import Schema, Table
from fieldtwin.tsx.module import IntelligentModule

Build = Callable[[Table, BuildContext, str], Device]


@dataclass(frozen=True, slots=True)
class DeviceKind:
    """One kind of device as users name it (``type = "TSX AEM 811"``, ``model = "TES 8EA"``)."""

    name: str
    family: Family
    schema: Schema
    build: Build  # a checked table, the build context, the table's field path
    core: type[IntelligentModule] | None = None  # a module kind's class, for the PLC
