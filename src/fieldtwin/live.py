"""The live status view of `fieldtwin run` (rich), and its plain-text twin."""

from __future__ import annotations

from typing import Any

from rich.console import Group
from rich.table import Table
from rich.text import Text

from fieldtwin.clock import S
from fieldtwin.plant import Plant
from fieldtwin.tsx.bus import ModuleState
from fieldtwin.words import format_hex


def _led(on: bool, colour: str) -> Text:
    return Text("●", style=colour) if on else Text("○", style="dim")


def render(plant: Plant, endpoints: list[str]) -> Group:
    """A rich renderable: the PLC rack and its modules, the TES, the endpoints."""
    parts: list[Any] = [
        Text(f"{plant.title}   t = {plant.clock.now / S:,.1f} s   speed {_speed(plant)}", "bold")
    ]
    plc = plant.plc
    if plc is not None:
        table = Table(title=f"{plc.model.name} {'RUN' if plc.running else 'STOP'}", expand=True)
        for col in ("slot", "module", "mode", "OK", "ERR", "F", "I,S", "IW0..IW7", "I F..0"):
            table.add_column(col, no_wrap=col != "module")
        for module in plc.modules:
            image = plc.image(module.rack, module.slot)
            leds = module.leds
            table.add_row(
                module.address,
                module.type_name,
                mode(module),
                _led(leds.get("OK", "off") != "off", "green"),
                _led(leds.get("ERR", "off") != "off", "red"),
                _led(leds.get("F", "off") != "off", "red"),
                str(int(image.fault)),
                " ".join(f"{w:04X}" for w in image.iw),
                f"{image.i_bits:016b}",
            )
        parts.append(table)
    if plant.tes:
        tes_table = Table(title="TES remote I/O", expand=True)
        for col in ("slave", "model", "status"):
            tes_table.add_column(col)
        for tes in plant.tes:
            tes_table.add_row(str(tes.slave), tes.model.name, tes_status(tes))
        parts.append(tes_table)
    parts.extend(Text(line, "cyan") for line in endpoints)
    parts.append(Text("Ctrl-C to stop", "dim"))
    return Group(*parts)


def mode(module: Any) -> str:
    """Run / Stop for a module that has them, else its state (self-test, off...)."""
    if module.running:
        return "Run"
    if module.has_run_stop and module.state is ModuleState.OPERATIONAL:
        return "Stop"
    return str(module.state.value)


def tes_status(tes: Any) -> str:
    """Power, status word and LEDs of a TES, on one line."""
    if not tes.powered:
        return "off"
    leds = " ".join(f"{name}={state}" for name, state in tes.leds.items())
    return f"on  status {format_hex(tes.status_word())}  {leds}"


def _speed(plant: Plant) -> str:
    return "max" if plant.speed is None else f"x{plant.speed:g}"


def plain_status(plant: Plant) -> list[str]:
    """One line per module: for logs and non-terminal output."""
    lines = [f"t = {plant.clock.now / S:.3f} s"]
    plc = plant.plc
    if plc is not None:
        for module in plc.modules:
            image = plc.image(module.rack, module.slot)
            words = " ".join(format_hex(w) for w in image.iw)
            lines.append(
                f"slot {module.address} {module.type_name}:"
                f" {mode(module)} {module.led_text} IW {words}"
            )
    for tes in plant.tes:
        lines.append(f"TES {tes.slave} {tes.model.name}: {tes_status(tes)}")
    return lines
