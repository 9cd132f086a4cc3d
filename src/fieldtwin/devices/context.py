"""What every device kind is built with: one build context per plant."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fieldtwin.clock import SimClock
from fieldtwin.devices.face import Device
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.plc import Plc


@dataclass(slots=True)
class BuildContext:
    """The clock, the PLC (None in a TES-only plant) and the plant file's directory.

    ``later`` holds wiring between devices (a DEM's sync output to its partners)
    that can only be done once every device of the plant is built; the plant
    builder runs it in file order, each step with its own field path.
    """

    clock: SimClock
    plc: Plc | None
    base_dir: Path
    name: str  # the plant file, as errors name it
    devices: list[Device] = field(default_factory=list)  # built so far, in file order
    later: list[Callable[[], None]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what devices said of their inputs

    def require_plc(self, where: str) -> Plc:
        if self.plc is None:
            raise ConfigError(f"{where}: a module needs a PLC")
        return self.plc

    def after_build(self, step: Callable[[], None]) -> None:
        self.later.append(step)

    def finish(self) -> None:
        steps, self.later = self.later, []
        for step in steps:
            step()
