"""The DEM 2412 and DEM 2413 (DEM 6.1, 7.2), with their console and plant-file side."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.dem24.inputs import TYPE1_24V, TYPE1_48V
from fieldtwin.tsx.dem24.module import Dem24Core


class Dem24(Dem24Core):
    """What the DEM 2412 and 2413 share; the subclasses set thresholds and codes."""

    def console_input(self, channel: int, text: str) -> None:
        from fieldtwin.tsx.dem24.plantkeys import console_value

        self.set_input(channel, console_value(text))

    def fault_names(self) -> Mapping[str, str]:
        return {
            "terminal_block": "TSX BLK4 terminal block removed",
            "supply": "external input supply lost",
            "pulses": "synchronization pulses no longer reach IN-SYN",
        }

    def inject_fault(self, name: str, active: bool) -> None:
        if name == "terminal_block":
            self.set_terminal_block(not active)
        elif name == "supply":
            self.set_supply(not active)
        elif name == "pulses" and self.pulse_source is not None:
            self.pulse_source.silenced = active
        elif name == "pulses":
            raise ConfigError("fault 'pulses': this module has no pulse source (sync key)")
        else:
            super().inject_fault(name, active)

    def configure_from_plant(self, table: Mapping[str, Any], where: str, base_dir: Path) -> None:
        from fieldtwin.tsx.dem24.plantkeys import configure

        configure(self, table, where, base_dir)

    def status_details(self) -> dict[str, str]:
        tb = self.timebase
        now = self.clock.now
        osc = [i for i, d in enumerate(self.detectors or []) if d.oscillating]
        return {
            "time": f"{tb.now(now)} ({tb.state.value})" if tb.ready else tb.state.value,
            "sync fault": "yes" if tb.fault else "no",
            "stack": f"{len(self.stack)}/{self.stack.size} (lost {self.stack.total_lost})",
            "logging": "active" if self.logging else "stopped",
            "selected": f"H'{self.selected():06X}'",
            "inputs": f"H'{self.inputs.levels():06X}'",
            "oscillating": ", ".join(map(str, osc)) or "none",
            "config": "default" if self.default_config else "user",
        }


class Dem2412(Dem24):
    """24 x 24 V DC inputs, code 777 (DEM 6.1, 6.2)."""

    type_name = "TSX DEM 2412"
    thresholds = TYPE1_24V
    hardware_codes = frozenset({777})
    software_codes = frozenset({777})
    version_text = "TSX DEM 2412 V1.0"


class Dem2413(Dem24):
    """24 x 48 V DC inputs, code 778 (DEM 6.1, 6.2)."""

    type_name = "TSX DEM 2413"
    thresholds = TYPE1_48V
    hardware_codes = frozenset({778})
    software_codes = frozenset({778})
    version_text = "TSX DEM 2413 V1.0"
