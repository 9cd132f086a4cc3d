"""A plant brought to life: a plain value (name, title, clock, PLC, devices).

It is built from a plant file (fieldtwin.plant.building) and opens nothing by
itself.  Besides the value it carries two handles its users reach through it:
``events``, the bus its devices publish on (the PLC's watchdog trip is wired to
it when built), and ``ports``, what has been opened for it (binder groups, the
recorder; fieldtwin.plant.ports).  ``close()``, ``record()`` and
``start_endpoints()`` are the Python API's short forms of the ports' own; a
session (fieldtwin.session) is what composes a whole run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from fieldtwin.clock import SimClock
from fieldtwin.devices.face import Device, Family, TesAddress
from fieldtwin.devices.module import ModuleDevice
from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import Tes, tes_core
from fieldtwin.plant.ports import Ports
from fieldtwin.plant.reading import PlantFile, recording_header
from fieldtwin.plant.tags import Tags
from fieldtwin.runtime.binder import Binding
from fieldtwin.runtime.door import Door
from fieldtwin.runtime.events import EventBus
from fieldtwin.tsx.plc import Plc

if TYPE_CHECKING:
    from fieldtwin.runtime.record import Recorder
    from fieldtwin.runtime.runner import Runner


@dataclass(slots=True)
class Plant:
    """A plant brought to life (in simulated time; `fieldtwin run` paces it)."""

    name: str
    title: str
    clock: SimClock
    plc: Plc | None
    devices: list[Device] = field(default_factory=list)  # in file order: modules, then TES
    speed: float | None = 1.0
    notes: list[str] = field(default_factory=list)  # what devices said of the file's inputs
    events: EventBus = field(default_factory=EventBus)  # what windows onto the plant observe
    source: PlantFile | None = None  # the file it was built from (a recording embeds it)
    # what the plant file's [[tag]] tables name, and its default trends (fieldtwin.plant.tags)
    tags: Tags = field(default_factory=Tags)
    ports: Ports = field(default_factory=Ports, repr=False, compare=False)
    # every command from outside runs at the door
    door: Door = field(default_factory=Door, repr=False, compare=False)

    # --- devices -----------------------------------------------------------

    @property
    def tes_devices(self) -> list[Device]:
        """The TES devices, in file order."""
        return [d for d in self.devices if d.family == Family.TES]

    @property
    def tes(self) -> list[Tes]:
        """The TES cores, in file order (Python users and tests reach them so)."""
        return [t for t in map(tes_core, self.tes_devices) if t is not None]

    def module_device(self, rack: int, slot: int) -> ModuleDevice:
        """The module in rack/slot (one inserted from Python gets the generic face)."""
        for device in self.devices:
            if isinstance(device, ModuleDevice) and (device.module.rack, device.module.slot) == (
                rack,
                slot,
            ):
                return device
        if self.plc is None:
            raise ConfigError("this plant has no PLC (add a [plc] table or [[module]] tables)")
        return ModuleDevice(self.plc.module(rack, slot), self.plc)

    def tes_device(self, slave: int, endpoint: str | None = None) -> Device:
        """The TES answering ``slave`` (on ``endpoint`` when given); two on different
        endpoints with that number need the endpoint."""
        found = [
            (d, a)
            for d in self.tes_devices
            if isinstance(a := d.address, TesAddress)
            and a.slave == slave
            and (endpoint is None or a.endpoint == endpoint)
        ]
        if len(found) == 1:
            return found[0][0]
        have = ", ".join(str(d.address) for d in self.tes_devices) or "none"
        if not found:
            where = f" on {endpoint}" if endpoint is not None else ""
            raise ConfigError(
                f"no TES with slave number {slave}{where} in this plant (have: {have})"
            )
        raise ConfigError(
            f"slave number {slave} answers on {len(found)} endpoints: name the endpoint,"
            f" e.g. tes {found[0][1].endpoint} {slave} ... (have: {have})"
        )

    def tes_by_slave(self, slave: int) -> Tes:
        """The TES core answering ``slave`` (plant.tes_device(slave) is its device)."""
        core = tes_core(self.tes_device(slave))
        if core is None:  # a family-TES device that is no fieldtwin TES
            raise ConfigError(f"slave number {slave} is no TES core of fieldtwin")
        return core

    # --- what is opened for it (fieldtwin.plant.ports) -------------------------

    @property
    def bindings(self) -> list[Binding]:
        """The binder groups opened for this plant (and what closes with them)."""
        return self.ports.bindings

    @property
    def recorder(self) -> Recorder | None:
        """The recorder writing what enters and leaves (plant.record), if any."""
        return self.ports.recorder

    @recorder.setter
    def recorder(self, recorder: Recorder | None) -> None:
        self.ports.recorder = recorder

    def start_endpoints(self, runner: Runner) -> list[str]:
        """Open the TES Modbus endpoints; returns one 'listening: ...' line each."""
        from fieldtwin.runtime.binder import MODBUS

        if self.recorder is not None and runner.tap is None:
            runner.set_tap(self.recorder)  # recorded since before the endpoints opened
        return self.ports.bind(self.devices, runner, (MODBUS,), self.events).lines

    def note_bound(self, groups: tuple[str, ...]) -> None:
        """The binder is about to open ``groups`` (a recording replays that)."""
        self.ports.note_bound(groups)

    def record(self, path: str | Path, runner: Runner | None = None) -> Recorder:
        """Record what enters and leaves the plant into ``path`` (docs/record.md), until
        ``plant.close()`` (or the recorder's ``close()``).  ``runner``: the one pumping
        the plant's endpoints (default: the PLC's).  Start it before the plant runs."""
        from fieldtwin.runtime.record import Recorder
        from fieldtwin.runtime.runner import Runner

        if self.recorder is not None:
            raise ConfigError(f"this plant is already recording into {self.recorder.path}")
        if self.clock.now or self.clock.fired:
            raise ConfigError(
                f"plant.record: start the recording before the plant runs (simulated time is"
                f" {self.clock.now / 1e6:g} s): a replay starts from the plant file at t = 0"
            )
        pacer = runner or (self.plc.runner if self.plc is not None else None)
        if self.source is None:
            raise ConfigError(
                "plant.record: this plant was not built from a plant file (build_plant,"
                " load_plant): a replay rebuilds the plant from its file"
            )
        header = recording_header(self.source, self.speed)
        recorder = Recorder(path, header, self.clock, self.devices, self.events, door=self.door)
        self.ports.set_recorder(recorder)
        if isinstance(pacer, Runner):
            pacer.set_tap(recorder)
        self.ports.add(recorder.close)
        return recorder

    def close(self) -> None:
        """Close what was opened for the plant (its ports, its recorder)."""
        self.ports.close()
