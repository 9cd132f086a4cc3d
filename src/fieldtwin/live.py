"""The live status view of `fieldtwin run` (rich), and its plain-text twin.

Both see the plant through the Device face only (fieldtwin.devices.face).  The
view fits the terminal: at 150 columns and more one line per module with a
column per LED and the input and output bits (Ixy,F..0, Oxy,F..0) in binary;
from 104 columns the LEDs share a column and the I and O bits are hex words;
below, each module's eight input words take two lines of their own column and
the O word sits under the I word (80 x 24 shows the default plant whole).
"""

from __future__ import annotations

from collections.abc import Sequence

from rich import box
from rich.console import Console, ConsoleOptions, Group, RenderResult
from rich.segment import Segment
from rich.style import Style
from rich.table import Table
from rich.text import Text

from fieldtwin.clock import S
from fieldtwin.devices.face import Device, DeviceStatus, Family, reading_text
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant import Plant
from fieldtwin.plant.tags import tag_value
from fieldtwin.runtime.runner import Runner
from fieldtwin.tsx.plc import Plc

WIDE = 150  # a column per LED, the input and output bits in binary
MEDIUM = 104  # one LED column, I and O bits in hex; below: words and I / O on two lines
_LIT = {"on": ("●", "green"), "blink": ("◐", "yellow"), "off": ("○", "dim")}
_ALARM = {"ERR", "F"}  # LEDs that are red when lit


class LiveView:
    """A renderable that lays itself out for the width it is given; with ``urls`` (the
    control and dashboard URLs) and ``height``, a footer naming them that stays on
    screen at every size: the view above it is cut to make room."""

    def __init__(
        self,
        plant: Plant,
        endpoints: list[str],
        runner: Runner | None = None,
        urls: Sequence[str] = (),
        height: int | None = None,
    ) -> None:
        self.plant = plant
        self.endpoints = endpoints
        self.runner = runner
        self.urls = list(urls)
        self.height = height

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        view = _render(self.plant, self.endpoints, options.max_width, self.runner)
        if not self.urls:
            yield view
            return
        footer = Text("\n".join([*self.urls, "Ctrl-C to stop"]), "bold cyan", overflow="fold")
        height = self.height if self.height is not None else options.size.height
        lines = console.render_lines(view, options.update(height=None), pad=False)[:-1]
        below = console.render_lines(footer, options.update(height=None), pad=False)
        room = max(0, height - len(below) - 1)  # one line for the cursor rich keeps
        if len(lines) > room:
            lines = [*lines[: max(0, room - 1)], [Segment("…", Style(dim=True))]][:room]
        for line in [*lines, *below]:
            yield from line
            yield Segment.line()


def footer_urls(lines: Sequence[str]) -> list[str]:
    """The control and dashboard URLs among the control API's start lines."""
    return [line for line in lines if line.startswith(("control: ", "dashboard: "))]


def render(
    plant: Plant,
    endpoints: list[str],
    runner: Runner | None = None,
    urls: Sequence[str] = (),
    height: int | None = None,
) -> LiveView:
    """A rich renderable: the PLC rack and its modules, the TES, the endpoints; with the
    ``runner``, the speed it reaches beside the speed asked; with ``urls``, a footer
    naming them that fits in ``height`` lines (default: the terminal's)."""
    return LiveView(plant, endpoints, runner, urls, height)


def _render(plant: Plant, endpoints: list[str], width: int, runner: Runner | None) -> Group:
    speed = _speed(plant) + _reached(plant, runner)
    parts: list[Table | Text] = [
        Text(f"{plant.title}   t = {plant.clock.now / S:,.1f} s   speed {speed}", "bold")
    ]
    if plant.plc is not None:
        plc = plant.plc
        title = f"{plc.model.name} {plc.mode}"
        parts.append(_modules(plant, _module_devices(plant), title, width))
        if plc.program is not None:
            parts.append(Text(program_line(plc), "green", overflow="fold"))
    for family, devices in _families(plant).items():
        parts.append(_family_table(family, devices, width))
        if width >= MEDIUM:  # each one's front (bit rows, words, readings) beneath
            parts.extend(_fronts(devices))
        elif plant.plc is None:  # no rack to make room for: the values at every width
            parts.extend(Text(values_line(d), "dim", overflow="fold") for d in devices)
    if width >= WIDE:
        parts.extend(_fronts([d for _, _, d in _module_devices(plant)], readings_only=True))
        parts.extend(tags_lines(plant))
    parts.extend(Text(line, "cyan", overflow="fold") for line in endpoints)
    parts.append(Text("Ctrl-C to stop", "dim"))
    return Group(*parts)


MAX_TAGS_SHOWN = 24  # tags the wide live view names (the dashboard and GET /tags show all)


def tags_lines(plant: Plant) -> list[Text]:
    """The plant's tags by name, each in its unit: ``tags: tank0.level 6411 mm  ...``."""
    if not plant.tags:
        return []
    shown = []
    for tag in list(plant.tags)[:MAX_TAGS_SHOWN]:
        try:
            shown.append(f"{tag.name} {tag_value(plant, tag).text}")
        except FieldtwinError:  # a module out of its slot
            shown.append(f"{tag.name} -")
    more = len(plant.tags) - len(shown)
    text = "tags: " + "  ".join(shown) + (f"  (+{more})" if more > 0 else "")
    return [Text(text, "magenta", overflow="fold")]


def _table(title: str, width: int) -> Table:
    compact = width < WIDE
    return Table(
        title=title,
        expand=not compact,
        box=box.SIMPLE_HEAD if compact else box.HEAVY_HEAD,
        padding=(0, 1) if not compact else (0, 0, 0, 1),
        show_edge=not compact,
    )


def _modules(plant: Plant, modules: list[tuple[int, int, Device]], title: str, width: int) -> Table:
    table = _table(title, width)
    wide, medium = width >= WIDE, MEDIUM <= width < WIDE
    leds = ["OK", "ERR", "F"] if wide else ["LEDs"]
    words = "IW0..IW7" if width >= MEDIUM else "IW0..3 / IW4..7"
    if wide:
        bit_columns: tuple[str, ...] = ("I F..0", "O F..0")
    elif medium:
        bit_columns = ("I", "O")
    else:
        bit_columns = ("I / O",)  # the output bits on the words' second line
    for col in ("slot", "module", "mode", *leds, "I,S", words, *bit_columns):
        table.add_column(col, no_wrap=True)
    assert plant.plc is not None
    for rack, slot, device in modules:
        status = device.status()
        image = plant.plc.image(rack, slot)
        iw = [f"{w:04X}" for w in image.iw]
        shown = " ".join(iw) if wide or medium else " ".join(iw[:4]) + "\n" + " ".join(iw[4:])
        if wide:  # a module without one of the LEDs (SCM 1.2: no ERR) leaves its cell empty
            lit = status.led_map
            lights = [_led(name, lit[name]) if name in lit else Text("") for name in leds]
        else:
            lights = [_leds(status)]
        o_bits = output_bits(plant.plc, rack, slot)
        if wide:
            bits = [f"{image.i_bits:016b}", f"{o_bits:016b}"]
        elif medium:
            bits = [f"{image.i_bits:04X}", f"{o_bits:04X}"]
        else:
            bits = [f"{image.i_bits:04X}\n{o_bits:04X}"]
        table.add_row(
            status.address,
            _kind(status),
            mode(status),
            *lights,
            str(int(image.fault)),
            shown,
            *bits,
        )
    return table


FAULT_MARK = "⚠"  # a device with a fault in force (set from the console, the API, the plant)


def _kind(status: DeviceStatus) -> Text:
    """The device's kind, marked when a fault is in force (the faults' names beside)."""
    text = Text(status.kind)
    if status.active_faults:
        names = ",".join(f.name for f in status.active_faults)
        text.append(f" {FAULT_MARK} {names}", style="bold red")
    return text


def faults_note(status: DeviceStatus) -> str:
    """``  faults: late_answer ms=200`` when faults are in force, else ``""``."""
    if not status.active_faults:
        return ""
    return "  faults: " + ", ".join(f.text() for f in status.active_faults)


def output_bits(plc: Plc, rack: int, slot: int) -> int:
    """Oxy,0..Oxy,F as the program wrote them (a DST's lamps; 0 for a module out)."""
    name = f"{rack}{slot}" if rack else f"{slot}"
    value = 0
    try:
        for bit in range(16):
            value |= (plc.read(f"O{name},{bit:X}") & 1) << bit
    except FieldtwinError:
        return 0
    return value


def _families(plant: Plant) -> dict[Family, list[Device]]:
    """Every device outside the PLC's rack (a TES...), by family, in file order."""
    found: dict[Family, list[Device]] = {}
    for device in plant.devices:
        if device.family != Family.MODULE:
            found.setdefault(device.family, []).append(device)
    return found


def _family_table(family: Family, devices: list[Device], width: int) -> Table:
    """One row per device of a family: its address as its columns, kind, state, LEDs."""
    table = _table(family.title or family.what, width)
    columns = [name for name, _ in devices[0].address.columns]
    for col in (*columns, family.key, "status", "LEDs"):
        table.add_column(col, no_wrap=col not in columns[:1], overflow="fold")
    for device in devices:
        status = device.status()
        word = dict(status.details).get("status", "")
        table.add_row(
            *(value for _, value in device.address.columns),
            _kind(status),
            f"{status.state} {word}".strip(),
            _leds(status),
        )
    return table


def _fronts(devices: list[Device], readings_only: bool = False) -> list[Text]:
    """``TES 1 front:  in: 0000...  readings: a0=2.000V``: each device's typed
    front panel (Device.panel()) on a line of its own; nothing for an empty front."""
    out = []
    for device in devices:
        panel = device.panel()
        if readings_only:
            lines = (
                ["readings: " + " ".join(map(reading_text, panel.readings))]
                if panel.readings
                else []
            )
        else:
            lines = panel.lines()
        if not readings_only:
            lines.extend(_analog_outputs(device.status()))
        if lines:
            head = f"{device.address.label} front:  "
            out.append(Text(head + "  ".join(lines), "dim", overflow="fold"))
    return out


def _analog_outputs(status: DeviceStatus) -> list[str]:
    """``["aout: a0=5.000V (H'4000')"]`` for a device with analog outputs, else ``[]``."""
    shown = [f"{o.name}={o.text()}" for o in status.outputs if not isinstance(o.value, bool)]
    return ["aout: " + " ".join(shown)] if shown else []


def values_text(device: Device) -> str:
    """``in H'0009'  out H'0000'  a0=7.351V a1=2.500V  aout: a0=5.000V (H'4000')``: a
    device's inputs and outputs (bit rows in hex, bit 0 the lowest), its readings in
    their unit and its analog outputs, in a few words; ``""`` for a device off."""
    status = device.status()
    if status.state == "off":
        return ""
    panel = device.panel()
    parts = []
    for row in panel.bits:
        if row.bits:
            value = sum(1 << i for i, on in enumerate(row.bits) if on)
            parts.append(f"{row.name} H'{value:0{max(4, (len(row.bits) + 3) // 4)}X}'")
    if panel.readings:
        parts.append(" ".join(map(reading_text, panel.readings)))
    parts.extend(_analog_outputs(status))
    return "  ".join(parts)


def values_line(device: Device) -> str:
    """``TES 1 values:  in H'0009'  out H'0000'``: one device's values, for the live
    view of a plant without a PLC below 104 columns."""
    return f"{device.address.label} values:  {values_text(device) or 'off'}"


def _module_devices(plant: Plant) -> list[tuple[int, int, Device]]:
    """Every module in the PLC's slots (one inserted from Python too), in slot order,
    with its rack and slot."""
    if plant.plc is None:
        return []
    return [(m.rack, m.slot, plant.module_device(m.rack, m.slot)) for m in plant.plc.modules]


def _led(name: str, state: str) -> Text:
    mark, colour = _LIT.get(state, ("?", "magenta"))
    if state == "on" and name in _ALARM:
        colour = "red"
    return Text(mark, style=colour)


def _leds(status: DeviceStatus) -> Text:
    text = Text()
    for index, (name, state) in enumerate(status.leds):
        if index:
            text.append(" ")
        text.append_text(_led(name, state))
        text.append(name, style="" if state != "off" else "dim")
    return text


def mode(status: DeviceStatus) -> str:
    """Run / Stop for a device that has them, else its state (self-test, off...)."""
    return status.mode if status.mode is not None else status.state


def device_line(device: Device) -> str:
    """``TES 1 TES 32EST: on  status H'0009'  Pwr=on ...  at tcp://...``: one device
    outside the rack, one line, from its face (its address's label and place)."""
    address = device.address
    status = device.status()
    head = f"{address.label} {status.kind}: "
    if status.state == "off":
        return f"{head}off  at {address.where}"
    word = dict(status.details).get("status", "")
    shown = f"status {word}  " if word else ""
    return f"{head}{status.state}  {shown}{status.leds_text()}  at {address.where}"


tes_line = device_line  # its former name


def _speed(plant: Plant) -> str:
    return "max" if plant.speed is None else f"x{plant.speed:g}"


def _reached(plant: Plant, runner: Runner | None) -> str:
    """`` (reached x312)`` when the speed reached is not the speed asked (issue 20)."""
    reached = None if runner is None else runner.speed_reached
    if reached is None or (
        plant.speed is not None and abs(reached - plant.speed) < 0.05 * plant.speed
    ):
        return ""
    slow = runner is not None and runner.lagging
    return f" ({'only ' if slow else ''}x{reached:.3g} reached)"


def plain_status(plant: Plant) -> list[str]:
    """One line per device: for logs and non-terminal output."""
    lines = [f"t = {plant.clock.now / S:.3f} s"]
    plc = plant.plc
    for rack, slot, device in _module_devices(plant):
        assert plc is not None
        status = device.status()
        words = " ".join(f"H'{w:04X}'" for w in plc.image(rack, slot).iw)
        lines.append(
            f"slot {status.address} {status.kind}: {mode(status)} {status.leds_text()} IW {words}"
            + faults_note(status)
        )
    if plc is not None and plc.program is not None:
        lines.append(program_line(plc))
    for devices in _families(plant).values():
        for d in devices:
            values = values_text(d)
            shown = f"  {values}" if values else ""
            lines.append(device_line(d) + faults_note(d.status()) + shown)
    return lines


def program_line(plc: Plc) -> str:
    """The program's state: running / held / stopped, the active steps, chosen W words."""
    program = plc.program
    assert program is not None
    if plc.fault is not None:
        state = f"stopped ({plc.fault})"
    elif not plc.running:
        state = "stopped"
    elif program.held is not None:
        state = f"held ({program.held})"
    else:
        state = "running"
    steps = ",".join(program.active_steps()) if program.layout is not None else ""
    if plc.watch == [f"W{i}" for i in range(8)]:
        words = "W0..7 " + " ".join(f"{plc.read(w):04X}" for w in plc.watch)
    else:
        words = " ".join(f"{w}={plc.read(w):04X}" for w in plc.watch)
    head = f"program {state}  task {program.cycles}"
    if program.layout is not None:
        head += f"  steps {steps or '-'}"
    if program.faults:
        head += f"  faults {len(program.faults)}"
    return f"{head}  {words}" if plc.watch else head
