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

import re

from fieldtwin.control.resources import Control, fault_json, output_json
from fieldtwin.devices.dem24 import Dem24Device
from fieldtwin.devices.face import Device, TesAddress
from fieldtwin.devices.module import ModuleDevice
from fieldtwin.devices.tes import TesDevice
from fieldtwin.errors import FieldtwinError
from fieldtwin.tsx.dem24.stack import Message, MessageType
from fieldtwin.tsx.discrete.module import DiscreteInputs, DiscreteOutputs
from fieldtwin.tsx.plc import Plc
from fieldtwin.words import format_hex

Json = dict[str, object]
LAST_MESSAGES = 8  # a DEM's newest stacked messages shown (DEM 4.2-2 layout)
TES_POINTS_MAX = 1023  # TES §4.2.4: the converter's 0..1023 points over the full scale


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
    tes = [
        tes_panel(d, ids.get(id(d), str(d.address)), plant.clock.now)
        for d in plant.devices
        if isinstance(d.address, TesAddress)
    ]
    return {
        "title": plant.title,
        "clock": control.clock_json(),
        "plc": None if plc is None else plc_panel(plc),
        "modules": modules,
        "tes": tes,
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


def _signed(value: object) -> int | None:
    if not isinstance(value, int):
        return None
    return value - 0x10000 if value & 0x8000 else value


def module_panel(device: ModuleDevice, plc: Plc, ident: str) -> Json:
    """One module's front: LEDs, I,S, the discrete bits, IW/OW words, decoded fields."""
    status = device.status()
    module = device.module
    a = device.address
    entry = plc.slot_entry(a.rack, a.slot)
    image = entry.image
    points = getattr(module, "points", 16)
    has_inputs = not isinstance(module, DiscreteOutputs)
    has_outputs = not isinstance(module, DiscreteInputs)
    details = dict(status.details)
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
        "decoded": _decoded(device, details),
        "inputs": list(device.inputs()),
        "faults": [fault_json(f) for f in device.faults().values()],
        "active_faults": [f.text() for f in status.active_faults],
        "outputs": [output_json(o) for o in status.outputs],
    }
    return out


def _decoded(device: ModuleDevice, details: dict[str, str]) -> Json:
    """What the kind's words mean, from its own status lines (and a DEM's stack)."""
    kind = device.kind
    if kind.startswith("TSX AEM"):
        return {
            "channels": [_aem_channel(ch, details.get(f"channel {ch}", "")) for ch in range(8)],
            "configuration": details.get("configuration", ""),
            "sampling": details.get("sampling", ""),
        }
    if isinstance(device, Dem24Device):
        stack = device.dem.stack
        messages = stack.peek()[-LAST_MESSAGES:]
        return {
            "time": details.get("time", ""),
            "stack": details.get("stack", ""),
            "fill": len(stack),
            "size": stack.size,
            "overflow": stack.total_lost > 0 or stack.lost > 0,
            "lost": stack.total_lost,
            "logging": details.get("logging", ""),
            "sync_fault": details.get("sync fault", ""),
            "messages": [_message(m) for m in reversed(messages)],
        }
    if kind.startswith("TSX SCM"):
        return {
            "activity": details.get("activity", ""),
            "channels": [
                {"channel": ch, "text": details.get(f"channel {ch}", "")} for ch in (0, 1)
            ],
        }
    return {}


def _aem_channel(channel: int, text: str) -> Json:
    """``4/20 mA, user 0..10000; = 5538; thresholds 1000/8000 bits 10``: the measurement
    (in the configured scaling), the range and the threshold bits, from the status line."""
    value = re.search(r"; = (-?\d+)", text)
    bits = re.search(r"bits ([01]{2})", text)
    return {
        "channel": channel,
        "text": text,
        "value": int(value.group(1)) if value else None,
        "range": text.split(",")[0].strip(),
        "sqrt": "sqrt" in text,
        "threshold_bits": bits.group(1) if bits else None,
    }


def _message(message: Message) -> Json:
    s = message.stamp
    stamp = (
        f"{s.year:04d}-{s.month:02d}-{s.day:02d} {s.hour:02d}:{s.minute:02d}:{s.second:02d}"
        f".{s.ms:03d}"
    )
    if message.type is MessageType.CHANGE:
        what = f"input {message.channel} -> {message.state}"
    else:
        states = message.body[4] | ((message.body[5] & 0xFF) << 16)
        what = f"overall inputs H'{states:06X}'"
    return {"stamp": stamp, "type": message.type.name.lower(), "what": what, "h": message.h}


def _names(device: Device) -> dict[str, str]:
    """A TES word's map name -> its address (``direct[0]`` -> ``H'005'``)."""
    found = {}
    for entry in device.objects().names():
        found[entry.name] = entry.address
    return found


def tes_panel(device: Device, ident: str, now: int) -> Json:
    """One TES's front: LEDs, every input and output, counters, analog, watchdog."""
    status = device.status()
    address = device.address
    assert isinstance(address, TesAddress)
    out: Json = {
        "id": ident,
        "kind": status.kind,
        "slave": address.slave,
        "endpoint": address.endpoint,
        "state": status.state,
        "leds": [[name, state] for name, state in status.leds],
        "status": dict(status.details).get("status", ""),
        "faults": [fault_json(f) for f in device.faults().values()],
        "active_faults": [f.text() for f in status.active_faults],
        # every analog output in the device's units (volts, milliamps), the word beside
        "analog_outputs": [output_json(o) for o in status.outputs if not isinstance(o.value, bool)],
    }
    if not isinstance(device, TesDevice) or status.state == "off":
        return {**out, "inputs": [], "outputs": [], "counters": [], "analog": [], "watchdog": None}
    tes = device.tes
    model = tes.model
    names = _names(device)
    objects = device.objects()

    def peek(name: str) -> int:
        return objects.peek(names[name]) if name in names else 0

    if "direct_io" in names:  # an analog model: bits 0..3 inputs, 8..B outputs (§6.4)
        direct = peek("direct_io") & 0xF
    else:
        direct = peek("direct[0]") | (peek("direct[1]") << 16)
    inputs = [bool(direct >> i & 1) for i in range(model.digital_inputs)]
    outputs = [tes.digital_output(i) for i in range(model.digital_outputs)]
    counters = []
    for i in range(model.digital_inputs):
        rise, fall = f"counter_rise[{i}]", f"counter_fall[{i}]"
        if f"{rise}.high" in names:
            counters.append(
                {
                    "input": i,
                    "rise": (peek(f"{rise}.high") << 16) | peek(f"{rise}.low"),
                    "fall": (peek(f"{fall}.high") << 16) | peek(f"{fall}.low"),
                }
            )
    unit = model.analog_range.unit
    analog = []
    for k in model.analog_inputs:
        word = peek(f"analog_input[{k}]")
        analog.append(
            {
                "input": f"a{k}",
                "level": round(tes.ai.level(k, now), 4),
                "unit": unit,
                "points": _signed(word),
                "full_scale": model.analog_range.full_scale,
            }
        )
    watchdog = peek("watchdog")
    return {
        **out,
        "inputs": inputs,
        "outputs": outputs,
        "counters": counters,
        "analog": analog,
        "watchdog": {
            "word": watchdog,
            "seconds": watchdog / 10,
            "led": dict(status.leds).get("Wdg", "off"),
        },
    }


__all__ = ["LAST_MESSAGES", "module_panel", "panels", "plc_panel", "tes_panel"]
