"""The dashboard's one look at the plant: ``GET /dashboard/state`` (docs/dashboard.md).

``panels(control)`` runs on the simulation's thread (a command through the
inbox, like every other request) and returns, in one JSON value, what the
page draws: the PLC's front (model, RUN/STOP, master-task period, clock and
speed), each module's front panel (its LEDs as its Device face lists them,
``I,S``, the discrete bits, the IW/OW words with their PL7 names, and the
fields its kind decodes) and each TES's front (Pwr/Run/Prm/Wdg, inputs,
outputs, counters, analog values in volts and points, watchdog).  It only
peeks: nothing it reads has a side effect (a TES's memorized inputs stay).
"""

from __future__ import annotations

from fieldtwin.control.resources import Control, fault_json, output_json
from fieldtwin.control.trends import tags_panel
from fieldtwin.devices.face import Device, Family, FrontPanel, Logged, Reading
from fieldtwin.devices.module import ModuleDevice
from fieldtwin.errors import FieldtwinError
from fieldtwin.tsx.plc import Plc
from fieldtwin.words import format_hex

Json = dict[str, object]
LAST_MESSAGES = 8  # a DEM's newest stacked messages shown (DEM 4.2-2 layout)


def panels(control: Control) -> Json:
    """The whole plant for the dashboard, as one JSON value."""
    plant = control.plant
    ids = {id(d): ident for ident, d in control.devices().items()}
    plc = plant.plc
    modules: list[Json] = []
    if plc is not None:
        for m in plc.modules:
            device = plant.module_device(m.rack, m.slot)
            modules.append(module_panel(device, plc, ids.get(id(device), str(device.address))))
    # every device outside the rack, by family, under the family's name ("tes"):
    # drawn from its face alone, whatever its kind
    families: dict[str, list[Json]] = {Family.TES.value: []}
    titles: dict[str, str] = {Family.TES.value: Family.TES.title}
    for d in plant.devices:
        if d.family != Family.MODULE:
            titles.setdefault(d.family.value, d.family.title or d.family.what)
            entry = device_panel(d, ids.get(id(d), str(d.address)))
            families.setdefault(d.family.value, []).append(entry)
    return {
        "title": plant.title,
        "clock": control.clock_json(),
        "plc": None if plc is None else plc_panel(plc),
        "modules": modules,
        **families,
        "families": [{"key": key, "title": title} for key, title in titles.items()],
        **tags_panel(plant),  # the tags, their values in their units, the default trends
    }


def plc_panel(plc: Plc) -> Json:
    program = plc.program
    return {
        "model": plc.model.name,
        "running": plc.running,
        "mode": plc.mode,  # RUN, STOP or FAULT (the watchdog: "fault" says why)
        "fault": plc.fault,
        "scan_ms": plc.scan_us / 1000,
        "program": None if program is None else {"cycles": program.cycles},
    }


def _word(plc: Plc, name: str) -> Json:
    try:
        value = plc.read(name)
    except FieldtwinError:
        return {"name": name, "value": None, "hex": "-"}
    return {"name": name, "value": value, "hex": format_hex(value)}


def _bits(plc: Plc, prefix: str, count: int) -> int | None:
    value = 0
    try:
        for bit in range(count):
            value |= (plc.read(f"{prefix},{bit:X}") & 1) << bit
    except FieldtwinError:
        return None
    return value


def module_panel(device: ModuleDevice, plc: Plc, ident: str) -> Json:
    """One module's front: LEDs, I,S, the discrete bits, IW/OW words, decoded fields."""
    status = device.status()
    panel = device.panel()
    module = device.module
    a = device.address
    entry = plc.slot_entry(a.rack, a.slot)
    image = entry.image
    points = getattr(module, "points", 16)
    has_inputs = module.shows_i_bits
    has_outputs = module.shows_o_bits
    details = dict(status.details)
    inputs = device.inputs()
    out: Json = {
        "id": ident,
        "kind": status.kind,
        "rack": a.rack,
        "slot": a.slot,
        "address": str(a),
        "present": entry.present,
        "state": status.state,
        "mode": status.mode,
        "leds": [[name, state] for name, state in status.leds],
        "is": int(image.fault),
        "points": points,
        "i_bits": image.i_bits if has_inputs else None,
        "o_bits": _bits(plc, f"O{a}", points) if has_outputs else None,
        "iw": [_word(plc, f"IW{a},{i}") for i in range(8)],
        "ow": [_word(plc, f"OW{a},{i}") for i in range(8)],
        "details": details,
        "decoded": _decoded(panel),
        "panel": panel_json(panel),
        "inputs": list(inputs),
        "input_kinds": {name: i.description for name, i in inputs.items()},
        "faults": [fault_json(f) for f in device.faults().values()],
        "active_faults": [f.text() for f in status.active_faults],
        "outputs": [output_json(o) for o in status.outputs],
    }
    return out


def _decoded(panel: FrontPanel) -> Json:
    """What the kind's words mean, as its typed front gives them: its fields by name,
    its readings as ``channels``, its log as ``messages`` (newest first)."""
    out: Json = dict(panel.fields)
    if panel.readings:
        out["channels"] = [reading_json(r) for r in panel.readings]
    if panel.log:
        out["messages"] = [logged_json(x) for x in panel.log[:LAST_MESSAGES]]
    return out


def reading_json(reading: Reading) -> Json:
    """A reading as the page draws it; a numbered one also as ``channel``/``input``."""
    name = reading.name
    number: object = int(name) if name.isdigit() else name
    return {
        "channel": number,
        "name": name,
        "text": reading.text,
        "value": reading.value,
        "unit": reading.unit,
        "flags": list(reading.flags),
        **dict(reading.more),
    }


def logged_json(item: Logged) -> Json:
    return {"stamp": item.stamp, "type": item.kind, "what": item.text, "h": "H" in item.flags}


def panel_json(panel: FrontPanel) -> Json:
    """The typed front as it is, for a page that draws any kind (a made-up one too)."""
    return {
        "leds": [[name, state] for name, state in panel.leds],
        "bits": [{"name": r.name, "bits": list(r.bits)} for r in panel.bits],
        "words": [{"name": w.name, "value": w.value} for w in panel.words],
        "readings": [reading_json(r) for r in panel.readings],
        "frozen": [reading_json(r) for r in panel.frozen],
        "fields": dict(panel.fields),
        "log": [logged_json(x) for x in panel.log],
    }


def device_panel(device: Device, ident: str) -> Json:
    """One device outside the rack (a TES...), from its face: its address as its parts
    (``endpoint``, ``slave``), LEDs, faults, outputs, the typed front; and, from the
    front's named rows, words and values, what a TES's page draws (inputs, outputs,
    counters, analog values in volts or milliamps and points, watchdog)."""
    status = device.status()
    address = device.address
    inputs = device.inputs()
    parts = {k: int(v) if v.isdigit() else v for k, v in address.columns}
    out: Json = {
        "id": ident,
        "kind": status.kind,
        "label": address.label,
        "where": address.where,
        **parts,
        "state": status.state,
        "leds": [[name, state] for name, state in status.leds],
        "status": dict(status.details).get("status", ""),
        "input_names": list(inputs),
        "input_kinds": {name: i.description for name, i in inputs.items()},
        "faults": [fault_json(f) for f in device.faults().values()],
        "active_faults": [f.text() for f in status.active_faults],
        "outputs_driven": [output_json(o) for o in status.outputs],
        # every analog output in the device's units (volts, milliamps), the word beside
        "analog_outputs": [output_json(o) for o in status.outputs if not isinstance(o.value, bool)],
    }
    panel = device.panel()
    out["panel"] = panel_json(panel)
    if status.state == "off":
        return {**out, "inputs": [], "outputs": [], "counters": [], "analog": [], "watchdog": None}
    watchdog = panel.word("watchdog")
    return {
        **out,
        "inputs": list(panel.row("in")),
        "outputs": list(panel.row("out")),
        "counters": [
            {"input": int(c.name) if c.name.isdigit() else c.name, "rise": c.value, **dict(c.more)}
            for c in panel.frozen
        ],
        "analog": [
            {"input": r.name, "level": r.value, "unit": r.unit, **dict(r.more)}
            for r in panel.readings
        ],
        "watchdog": None
        if watchdog is None
        else {
            "word": watchdog,
            "seconds": panel.field("watchdog_s"),
            "led": dict(status.leds).get("Wdg", "off"),
        },
    }


def tes_panel(device: Device, ident: str, now: int = 0) -> Json:
    """One TES's front (its former name; ``now`` is not used)."""
    return device_panel(device, ident)


__all__ = ["LAST_MESSAGES", "device_panel", "module_panel", "panels", "plc_panel", "tes_panel"]
