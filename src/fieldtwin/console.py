"""The programming terminal of the twin: `fieldtwin console [PLANT]`.

Every command returns its output lines; the formats are stable and documented
in docs/console.md (e.g. ``IW5,0 = H'1008'``).  An error is a ConfigError whose
message names the token at fault and what is allowed.

The stand-alone console reads the files its user names (``prog load FILE``, a
``csv`` signal), within fieldtwin.textfile's bounds.  The control API's console
(``Console(plant, files=False)``: ``POST /console``, ``console --attach``) reads
none: ``prog load -`` takes the program's text that comes with the line, and a
command naming a file is refused, naming the verb (docs/control.md).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable
from typing import ClassVar, TextIO

from fieldtwin.clock import MS, S
from fieldtwin.console_prog import HELP as PROG_HELP
from fieldtwin.console_prog import is_internal, prog_command
from fieldtwin.console_syntax import (
    canonical_name,
    integer,
    latin1,
    looks_like_object,
    module_address,
    next_value,
    one_argument,
    parse_duration,
    result_lines,
    split_line,
    value_of,
)
from fieldtwin.console_trace import USAGE as TRACE_USAGE
from fieldtwin.console_trace import ConsoleTrace
from fieldtwin.devices.face import Device, DeviceStatus, Family, device_id
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.live import device_line
from fieldtwin.plant import Plant, outage
from fieldtwin.plant.tags import Tag, raw_value, raw_word, tag_value
from fieldtwin.runtime.door import Command, Handler
from fieldtwin.scenario import ScenarioRun, read_scenario
from fieldtwin.signals.spec import file_in_spec
from fieldtwin.tsx.addressing import parse_object
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.txt import ExchangeTimeout
from fieldtwin.words import format_hex, parse_word

HELP = {
    "read": "read OBJECT|TAG...        IW5,0  OW5,0,C  I5,3  I5,S  W100  tank1.level"
    " (a name alone reads it too; a tag in its unit)",
    "write": "write OBJECT|TAG VALUE    OW5,0,C 1   OW5,1 H'00FF'   O5,2 1   W100 30"
    "   (outputs OW/O and internal W, B, CW, SY, SW; inputs are read-only; a tag in its unit)",
    "exchange": 'exchange M C [send W...] [text "..."] [length L] [recv N] [txt I] [timeout S]\n'
    "                           e.g. exchange H'0563' H'40' send H'00A0' 30 recv 0",
    "advance": "advance DURATION          advance 11   advance 250ms   advance 2min",
    "time": "time                      the simulated time",
    "status": "status [MODULE]           module state, mode, LEDs, registers (MODULE = 5 or 23)",
    "input": "input MODULE NAME VALUE  set an input as the module takes it"
    " (input 5 0 2.5V, input 4 3 1, input 7 0.CTS 0); input TAG VALUE for a tagged input",
    "signal": "signal MODULE NAME KIND key=value...\n"
    "                           e.g. signal 5 0 sine offset=5 amplitude=2 period_s=60",
    "fault": "fault MODULE NAME on|off [key=value...]  inject or clear a fault;"
    " 'faults MODULE' lists the names",
    "faults": "faults MODULE             the faults a module can be given (* in force)",
    "outputs": "outputs MODULE            the outputs it drives, in its units",
    "leds": "leds MODULE               the front-panel LEDs: OK=on ERR=off F=off",
    "power": "power break SECONDS       cut the PLC supply",
    "remove": "remove MODULE             pull a module out under power",
    "insert": "insert MODULE             put it back (it runs its self-test)",
    "plc": "plc run|stop|cold|hot     PLC mode, cold restart (SY0), hot restart (SY1)",
    "txt": "txt I [reset]             a Text Block's outputs; reset ends its exchange (TXTi,S = 1)",
    "tes": "tes [ENDPOINT] SLAVE read ADDR [N] | peek ADDR [N] | write ADDR VALUE"
    " | input I VALUE | signal I KIND key=value... | fault NAME on|off | faults | status | leds"
    " | outputs | power-cycle [SECONDS]",
    "trace": f"{TRACE_USAGE}  the traffic on the wire; each advance shows its own",
    "scenario": "scenario FILE             run a scenario file (docs/scenarios.md) to its end",
    "prog": PROG_HELP,
    "help": "help [COMMAND]",
    "quit": "quit",
}


ADVANCE_STEP_US = 100 * MS  # Ctrl-C is looked at between two steps of an advance


def with_text(line: str, text: str | None) -> str:
    """A console line and the text that comes with it, as one command line is recorded
    (``LINE\nTEXT``); ConfigError when the line carries a text already."""
    if text is None:
        return line
    if "\n" in line:
        head = line.partition("\n")[0].strip()
        raise ConfigError(
            f"{head!r}: give the text after the line's first newline or as its text, not both"
        )
    return f"{line}\n{text}"


class Console:
    """Executes console commands against a plant."""

    def __init__(
        self,
        plant: Plant,
        *,
        interrupted: Callable[[], bool] = lambda: False,
        progress: Callable[[str], None] | None = None,
        files: bool = True,
        modes: Callable[[str, int], list[str]] | None = None,
    ) -> None:
        """``interrupted`` is asked between the steps of an ``advance`` (the interactive
        terminal's Ctrl-C); ``progress`` is told when a long one starts.  ``files``
        False is the control API's console: no command reads a file.  ``modes`` is a
        running plant's (the control API's): ``advance`` and ``power break`` start the
        runner mode ``modes(name, duration_us)`` and answer at once, so that nothing
        holds the plant's commands while simulated time runs (docs/control.md)."""
        self.plant = plant
        self.modes = modes
        self.interrupted = interrupted
        self.progress = progress
        self.files = files
        self.trace = ConsoleTrace(plant.events)
        # what runs a scenario's control-API steps where nothing serves the plant's door
        # (``fieldtwin console``: the CLI gives the handler of a Control made for it)
        self.call: Handler | None = None
        self._commands: dict[str, Callable[[list[str]], list[str]]] = {
            "read": self._read,
            "write": self._write,
            "exchange": self._exchange,
            "advance": self._advance,
            "time": lambda args: [self._time()],
            "status": self._status,
            "input": self._input,
            "signal": self._signal,
            "fault": self._fault,
            "faults": self._faults,
            "outputs": self._outputs,
            "leds": self._leds,
            "power": self._power,
            "remove": self._remove,
            "insert": self._insert,
            "plc": self._plc_mode,
            "txt": self._txt,
            "tes": self._tes,
            "trace": self.trace.command,
            "scenario": self._scenario,
            "help": self._help,
        }
        self._prog = prog_command(lambda: self.plc, files=files)

    @property
    def plc(self) -> Plc:
        if self.plant.plc is None:
            raise ConfigError("this plant has no PLC (add a [plc] table or [[module]] tables)")
        return self.plant.plc

    def execute(self, line: str, text: str | None = None) -> list[str]:
        """Run one command line; returns its output lines (through the plant's door:
        a recording sees it).

        ``text`` is the text that comes with the line (``prog load -`` takes a
        program's); it may also follow the line's first newline.  It is recorded with
        the line, as ``LINE\nTEXT``."""
        # a value through the plant's door (fieldtwin.runtime.door): what observes the
        # commands (a recording) sees it; this console runs it
        lines = self.plant.door.dispatch(Command.line(with_text(line, text)), self.handle)
        assert isinstance(lines, list)
        return lines

    def handle(self, command: Command) -> list[str]:
        """Run a console-line command the door hands over (its line, and its text after
        the first newline); its output lines."""
        return self._execute(command.name)

    def _execute(self, full: str) -> list[str]:
        line, newline, attached = full.partition("\n")
        text = attached if newline and attached.strip() else None
        try:
            words = split_line(line)
        except ValueError as exc:
            raise ConfigError(f"cannot split {line.strip()!r}: {exc}") from None
        name = words[0].lower() if words else ""
        if text is not None and name != "prog":
            shown = line.strip() or "an empty line"
            raise ConfigError(
                f"{shown!r}: takes no text after its line (only 'prog load -' does: the"
                " text of a program)"
            )
        if not words:
            return []
        args = words[1:]
        if name == "prog":
            return self._prog(args, text)
        if len(words) == 3 and words[1] == "=":  # OW5,0,C = 1
            return self._write([words[0], words[2]])
        command = self._commands.get(name)
        if command is not None:
            return command(args)
        if looks_like_object(words[0]) or self.plant.tags.get(words[0]) is not None:
            return self._read(words)
        raise ConfigError(f"unknown command {words[0]!r} (allowed: {', '.join(HELP)})")

    # --- objects -------------------------------------------------------------

    def _read(self, args: list[str]) -> list[str]:
        if not args:
            raise ConfigError("read: name at least one object or tag, e.g. read IW5,0")
        return [self._read_one(name) for name in args]

    def _read_one(self, name: str) -> str:
        """``IW5,0 = H'1008'`` (as ever, tagged or not); a tag: ``tank1.level = 5001 mm  (W1)``."""
        tag = self.plant.tags.get(name)
        if tag is not None:
            return f"{tag.name} = {tag_value(self.plant, tag).text}  ({tag.source.text})"
        if self.plant.plc is None and self.plant.tags:
            raise ConfigError(f"read: no tag {name!r} (allowed: {self.plant.tags.allowed()})")
        try:
            line = f"{canonical_name(name)} = {self._show(name)}"
        except ConfigError as exc:
            if self.plant.tags and not looks_like_object(name):
                raise ConfigError(
                    f"read: {name!r} is neither an object nor a tag"
                    f" (tags: {self.plant.tags.allowed()}): {exc}"
                ) from None
            raise
        return line

    def _show(self, name: str) -> str:
        value = self.plc.read(name)
        if name.upper().startswith("W") or is_internal(name):
            return str(value)
        ref = parse_object(name)
        return str(value) if ref.is_bit else format_hex(value)

    def _write(self, args: list[str]) -> list[str]:
        if len(args) != 2:
            raise ConfigError("write: takes OBJECT VALUE, e.g. write OW5,0,C 1")
        name, token = args
        tag = self.plant.tags.get(name)
        if tag is not None:
            return self._write_tag(tag, token)
        self.plc.write(name, parse_word(token))
        return [f"{canonical_name(name)} = {self._show(name)}"]

    def _write_tag(self, tag: Tag, token: str) -> list[str]:
        """``write tank1.level 2.5``: a number in the tag's unit, back to its raw word."""
        source = tag.source
        if source.kind in ("input", "output"):
            verb = "input" if source.kind == "input" else "write"
            raise ConfigError(
                f"write: {tag.name} is the {source.kind} {source.text}"
                + (
                    f" (allowed: {verb} {tag.name} VALUE)"
                    if verb == "input"
                    else " of a device (allowed: a tag of an object or a register)"
                )
            )
        try:
            raw = raw_word(tag, float(token)) if tag.scale is not None else parse_word(token)
        except ValueError:
            raise ConfigError(f"write {tag.name}: {token!r} is not a number") from None
        if source.device is None:
            self.plc.write(source.name, raw)
        else:
            self._module(source.device).objects().write(source.name, raw)
        return [self._read_one(tag.name)]

    # --- Text Blocks -----------------------------------------------------------

    def _exchange(self, args: list[str]) -> list[str]:
        if len(args) < 2:
            raise ConfigError('exchange: takes M C [send W...] [text "..."] [recv N] ...')
        m, c = parse_word(args[0]), parse_word(args[1])
        options: dict[str, str] = {}
        send: list[int] = []
        it = iter(args[2:])
        mode = None
        for token in it:
            key = token.lower()
            if key in ("send", "text", "recv", "txt", "timeout", "length"):
                mode = key
                if key != "send":
                    options[key] = next_value(it, token)
                continue
            if mode != "send":
                raise ConfigError(
                    f'exchange: unexpected {token!r} (allowed: send W..., text "...", length L,'
                    " recv N, txt I, timeout S)"
                )
            send.append(parse_word(token))
        txt = integer(options.pop("txt", "0"), "exchange txt")
        recv = options.pop("recv", None)
        recv_bytes = 0 if recv is None else integer(recv, "recv")
        text = latin1(options.pop("text")) if "text" in options else None
        length = integer(options.pop("length"), "exchange length") if "length" in options else None
        timeout_s = parse_duration(options.pop("timeout")) if "timeout" in options else 1200.0
        try:
            result = self.plc.exchange(
                m,
                c,
                None if text is not None else send,
                txt=txt,
                recv_bytes=recv_bytes,
                send_bytes=text,
                length=length,
                timeout_s=timeout_s,
            )
        except ExchangeTimeout as exc:
            raise ExchangeTimeout(
                f"{exc}; 'txt {txt}' shows it, 'txt {txt} reset' ends it"
            ) from None
        return result_lines(txt, result)

    def _txt(self, args: list[str]) -> list[str]:
        if not args or len(args) > 2 or (len(args) == 2 and args[1].lower() != "reset"):
            raise ConfigError("txt: takes I [reset], e.g. txt 0 reset")
        index = integer(args[0], "txt")
        if index < 0:
            raise ConfigError(f"txt: {args[0]!r} not allowed (allowed 0 or more)")
        if len(args) == 2:  # the Text Block's R input
            self.plc.reset_text_block(index)
        tb = self.plc.text_block(index)
        if tb.result is None or not tb.done:
            return [f"TXT{index}: {tb.state.value}"]
        return result_lines(index, tb.result)

    # --- time ----------------------------------------------------------------------

    def _time(self) -> str:
        return f"t = {self.plant.clock.now / S:.3f} s"

    def _advance(self, args: list[str]) -> list[str]:
        """In steps of ADVANCE_STEP_US, so that Ctrl-C stops it between two steps with
        the plant as it stands (docs/console.md)."""
        if len(args) != 1:
            raise ConfigError("advance: takes one duration, e.g. advance 11 or advance 250ms")
        left = round(parse_duration(args[0]) * S)
        if self.modes is not None:
            return self.modes("advance", left)
        if self.progress is not None and left > ADVANCE_STEP_US:
            self.progress(
                f"advancing to t = {(self.plant.clock.now + left) / S:.3f} s (Ctrl-C interrupts)"
            )
        while left > 0:
            step = min(left, ADVANCE_STEP_US)
            if self.plant.plc is not None:
                self.plant.plc.advance(step / S)
            else:
                self.plant.clock.advance(step)
            left -= step
            if left > 0 and self.interrupted():
                return [f"interrupted  {self._time()}", *self.trace.pending()]
        return [self._time(), *self.trace.pending()]

    # --- scenarios (docs/scenarios.md) ---------------------------------------------------

    def _scenario(self, args: list[str]) -> list[str]:
        """``scenario FILE``: its steps and expectations from now, simulated time run to
        its end; a line per outcome and the result (an error naming the first failure)."""
        path = one_argument(args, "scenario FILE")
        if not self.files:
            raise ConfigError(
                "scenario: reads a file, not allowed here (POST /scenarios takes the"
                " scenario's text: docs/scenarios.md)"
            )
        run = ScenarioRun(self.plant, read_scenario(path), call=self.call, line=self.handle)
        run.start()
        try:
            lines = self._advance([f"{(run.end_us - self.plant.clock.now) / S!r}"])
        finally:
            run.cancel()
        result = run.result
        if not result.passed:
            shown = [*result.lines()[:-1], *lines]
            raise ConfigError("\n".join([*shown, result.summary()]))
        return [*result.lines()[:-1], *lines, result.summary()]

    # --- devices: one set of verbs for a module and a TES (the Device face) ----------

    def _module(self, token: str) -> Device:
        """A module by its address (``5``, ``23``), or any device by its id in the
        control API (``tes1``, ``tes1@2``): the verbs are the same for every device."""
        devices = self.plant.devices
        for device in devices:
            if device_id(device, devices) == token.strip():
                return device
        rack, slot = module_address(token)
        return self.plant.module_device(rack, slot)

    def _status(self, args: list[str]) -> list[str]:
        if self.plant.plc is None and not args:
            return [self._time(), *self._tes_status()]
        if args and (device := self._module(args[0])).family != Family.MODULE:
            return device_status(device)
        plc = self.plc
        modules = (
            [self._module(args[0])]
            if args
            else [self.plant.module_device(m.rack, m.slot) for m in plc.modules]
        )
        lines = [f"PLC {plc.model.name} {plc.mode}  {self._time()}"]
        if plc.fault is not None:
            lines.append(f"fault: {plc.fault}")
        slots = {
            id(self.plant.module_device(m.rack, m.slot)): (m.rack, m.slot) for m in plc.modules
        }
        for device in modules:
            lines.append("")
            status = device.status()
            lines.extend(f"{key}: {value}" for key, value in status.details)
            lines.extend(fault_and_output_lines(status))
            rack, slot = slots[id(device)]
            iw = " ".join(format_hex(w) for w in plc.image(rack, slot).iw)
            ow = " ".join(format_hex(w) for w in plc.output_words(rack, slot))
            lines.append(f"IW: {iw}")
            lines.append(f"OW: {ow}")
            lines.append(f"I: {plc.image(rack, slot).i_bits:016b} (F..0)")
            lines.extend(device.panel().lines())
        if not args and self.plant.tes_devices:
            lines.extend(["", *self._tes_status()])
        return lines

    def _input(self, args: list[str]) -> list[str]:
        if len(args) == 2 and (tag := self.plant.tags.get(args[0])) is not None:
            return self._input_tag(tag, args[1])
        if len(args) != 3:
            raise ConfigError(
                "input: takes MODULE CHANNEL VALUE, e.g. input 5 0 2.5V, or TAG VALUE"
                + (f" (tags: {self.plant.tags.allowed()})" if self.plant.tags else "")
            )
        return set_input(self._module(args[0]), f"input {args[0]}", args[1:])

    def _input_tag(self, tag: Tag, token: str) -> list[str]:
        """``input pump3.run on``: the tagged input set as its device takes it (a plain
        number of a scaled tag is in the tag's unit)."""
        source = tag.source
        if source.kind != "input" or source.device is None:
            raise ConfigError(
                f"input: {tag.name} is {source.text}, not an input"
                f" (allowed: write {tag.name} VALUE for an object or a register)"
            )
        value = token
        if tag.scale is not None:
            with contextlib.suppress(ValueError):  # "12mA", "on": as the device takes it
                value = f"{raw_value(tag, float(token)):g}"
        device = self._module(source.device)
        return set_input(device, f"input {tag.name}", [source.name, value])

    def _signal(self, args: list[str]) -> list[str]:
        if len(args) < 3:
            raise ConfigError(
                "signal: takes MODULE CHANNEL KIND key=value..., e.g. signal 5 0 sine"
            )
        return set_signal(self._module(args[0]), f"signal {args[0]}", args[1:], self.files)

    def _fault(self, args: list[str]) -> list[str]:
        if len(args) < 3:
            raise ConfigError(
                "fault: takes MODULE NAME on|off [key=value...], e.g. fault 5 terminal_block on"
            )
        return set_fault(self._module(args[0]), f"fault {args[0]}", args[1:])

    def _faults(self, args: list[str]) -> list[str]:
        if len(args) != 1:
            raise ConfigError("faults: takes MODULE")
        return list_faults(self._module(args[0]))

    def _outputs(self, args: list[str]) -> list[str]:
        return list_outputs(self._module(one_argument(args, "outputs MODULE")))

    def _leds(self, args: list[str]) -> list[str]:
        return [self._module(one_argument(args, "leds MODULE")).status().leds_text()]

    def _power(self, args: list[str]) -> list[str]:
        if len(args) != 2 or args[0] != "break":
            raise ConfigError("power: takes 'break SECONDS', e.g. power break 2")
        if self.modes is not None:
            self.plc  # noqa: B018 - a plant without a PLC is refused here
            return self.modes("power break", round(parse_duration(args[1]) * S))
        self.plc.power_break(parse_duration(args[1]))
        return [f"power back  {self._time()}"]

    def _remove(self, args: list[str]) -> list[str]:
        rack, slot = module_address(one_argument(args, "remove MODULE"))
        self.plc.remove(rack, slot)
        return [f"module rack {rack} slot {slot} removed"]

    def _insert(self, args: list[str]) -> list[str]:
        rack, slot = module_address(one_argument(args, "insert MODULE"))
        self.plc.reinsert(rack, slot)
        return [f"module rack {rack} slot {slot} inserted"]

    def _plc_mode(self, args: list[str]) -> list[str]:
        actions = {
            "run": self.plc.start,
            "stop": self.plc.stop,
            "cold": self.plc.cold_restart,
            "hot": self.plc.hot_restart,
        }
        mode = one_argument(args, "plc run|stop|cold|hot").lower()
        if mode not in actions:
            raise ConfigError(f"plc: {mode!r} not allowed (allowed: run, stop, cold, hot)")
        actions[mode]()
        done = {"cold": " (cold restart)", "hot": " (hot restart)"}.get(mode, "")
        fault = [] if self.plc.fault is None else [f"fault: {self.plc.fault}"]
        return [f"PLC {self.plc.mode}{done}", *fault]

    def _tes_status(self) -> list[str]:
        """One line per device outside the PLC's rack (every TES), from its face."""
        return [device_line(d) for d in self.plant.devices if d.family != Family.MODULE]

    # --- TES -------------------------------------------------------------------------

    def _tes(self, args: list[str]) -> list[str]:
        """``tes [ENDPOINT] SLAVE VERB ...``: the endpoint may be left out when one TES
        answers that slave number."""
        if len(args) < 2:
            raise ConfigError(HELP["tes"])
        endpoint = None
        if not args[0].isdigit() and len(args) >= 3 and args[1].isdigit():
            endpoint, args = args[0], args[1:]
        try:
            slave = int(args[0])
        except ValueError:
            raise ConfigError(f"tes: {args[0]!r} is not a slave number") from None
        device = self.plant.tes_device(slave, endpoint)
        head = f"tes {slave}" if endpoint is None else f"tes {endpoint} {slave}"
        verb, rest = args[1].lower(), args[2:]
        words = self._TES_VERBS.get(verb)
        if words is None or not words[0] <= len(rest) <= words[1]:
            raise ConfigError(f"tes: {' '.join(args[1:])!r} not understood ({HELP['tes']})")
        return words[2](self, device, head, rest)

    def _tes_read(self, device: Device, head: str, rest: list[str], peek: bool) -> list[str]:
        start = parse_word(rest[0])
        count = integer(rest[1], "tes read N") if len(rest) > 1 else 1
        if not 1 <= count <= 256:
            raise ConfigError(f"tes read: N = {count} not allowed (allowed 1..256)")
        words = device.objects()
        read = words.peek if peek else words.read  # a read is a master's, with its effects
        return [
            f"{head} {format_hex(a, 3)} = {format_hex(read(str(a)))}"
            for a in range(start, start + count)
        ]

    def _tes_write(self, device: Device, head: str, rest: list[str]) -> list[str]:
        address, value = parse_word(rest[0]), parse_word(rest[1])
        device.objects().write(str(address), value)
        return [
            f"{head} {format_hex(address, 3)} = {format_hex(device.objects().peek(str(address)))}"
        ]

    def _tes_power_cycle(self, device: Device, head: str, rest: list[str]) -> list[str]:
        """``power-cycle [SECONDS]``: off and on at once, or on again SECONDS later (an
        outage on the simulated clock: fieldtwin.plant.outage)."""
        duration = parse_duration(rest[0]) if rest else None
        back = outage.power_cycle(self.plant.clock, device, duration, head)
        if back is None:
            return [f"{head} power cycled"]
        return [f"{head} power off until t = {back / S:.3f} s"]

    _TES_VERBS: ClassVar[
        dict[str, tuple[int, int, Callable[[Console, Device, str, list[str]], list[str]]]]
    ] = {
        "read": (1, 2, lambda c, d, h, r: c._tes_read(d, h, r, peek=False)),
        "peek": (1, 2, lambda c, d, h, r: c._tes_read(d, h, r, peek=True)),
        "write": (2, 2, lambda c, d, h, r: c._tes_write(d, h, r)),
        "input": (2, 2, lambda c, d, h, r: set_input(d, f"{h} input", r)),
        "signal": (2, 64, lambda c, d, h, r: set_signal(d, f"{h} signal", r, c.files)),
        "fault": (2, 9, lambda c, d, h, r: set_fault(d, f"{h} fault", r)),
        "faults": (0, 0, lambda c, d, h, r: list_faults(d)),
        "status": (0, 0, lambda c, d, h, r: device_status(d)),
        "outputs": (0, 0, lambda c, d, h, r: list_outputs(d)),
        "leds": (0, 0, lambda c, d, h, r: [d.status().leds_text()]),
        "power-cycle": (0, 1, lambda c, d, h, r: c._tes_power_cycle(d, h, r)),
    }

    def _help(self, args: list[str]) -> list[str]:
        if args:
            key = args[0].lower()
            if key not in HELP:
                raise ConfigError(f"help: unknown command {args[0]!r} (allowed: {', '.join(HELP)})")
            return [HELP[key]]
        return list(HELP.values())


def set_input(device: Device, head: str, args: list[str]) -> list[str]:
    """``NAME VALUE`` on any device: ``input 5 0 = 2.5V``, ``tes 1 input 3 = true``."""
    name, value = args
    note = device.input(name).set(value)
    return [f"{head} {name} = {value}", *([f"note: {note}"] if note else [])]


def set_signal(device: Device, head: str, args: list[str], files: bool = True) -> list[str]:
    """``NAME KIND key=value...``: the input driven by a signal (docs/signals.md).
    With ``files`` False (the control API's console) a signal that reads a file is
    refused before anything is read."""
    name, kind, *pairs = args
    spec: dict[str, object] = {"kind": kind}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep:
            raise ConfigError(f"signal: {pair!r} is not key=value")
        spec[key] = value_of(value)
    found = None if files else file_in_spec(spec, f"{head} {name}")
    if found is not None:
        raise ConfigError(
            f"{found} reads a file: files are only for the stand-alone console"
            " (fieldtwin console PLANT) and the plant file, not through the control API"
            " (allowed here: every other kind of docs/signals.md)"
        )
    device.input(name).drive(spec, where=f"{head} {name}")
    return [f"{head} {name} = {kind}"]


def set_fault(device: Device, head: str, args: list[str]) -> list[str]:
    """``NAME on|off [key=value...]``: a TES's ``late_answer on ms=200`` takes parameters."""
    name, state, *pairs = args
    state = state.lower()
    if state not in ("on", "off"):
        raise ConfigError(f"fault: {args[1]!r} not allowed (allowed: on, off)")
    params: dict[str, int | float] = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        value = value_of(text)
        if not sep or isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"fault {name}: {pair!r} is not key=NUMBER (e.g. ms=200)")
        params[key] = value
    device.fault(name).set(state == "on", **params)
    return [f"{head} {name} {state}" + "".join(f" {pair}" for pair in pairs)]


def list_faults(device: Device) -> list[str]:
    """One line per fault that applies (``name: description``), then one line per fault
    in force, marked ``*``: ``* late_answer active ms=200``."""
    faults = device.faults().values()
    lines = [f"{fault.name}: {fault.description}" for fault in faults]
    for fault in faults:
        params = fault.in_force()
        if params is not None:
            given = "".join(f" {k}={v:g}" for k, v in params.items())
            lines.append(f"* {fault.name} active{given}")
    return lines or ["(none)"]


def list_outputs(device: Device) -> list[str]:
    """``a4 = 4.500V (H'3FFF')``: every output the device drives, in its units."""
    return [f"{o.name} = {o.read().text()}" for o in device.outputs().values()] or ["(none)"]


def device_status(device: Device) -> list[str]:
    """A device outside the rack: its line, then (when it is on) its faults in force,
    its outputs and its typed front panel (bit rows, words, readings, frozen values)."""
    status = device.status()
    if status.state == "off":
        return [device_line(device)]
    return [device_line(device), *fault_and_output_lines(status), *device.panel().lines()]


def fault_and_output_lines(status: DeviceStatus) -> list[str]:
    """``faults: late_answer ms=200`` and ``outputs: 0=1 a4=4.500V (H'3FFF')`` for ``status``."""
    lines = []
    if status.active_faults:
        lines.append("faults: " + ", ".join(f.text() for f in status.active_faults))
    if status.outputs:
        lines.append("outputs: " + " ".join(f"{o.name}={o.text()}" for o in status.outputs))
    return lines


def run_script(
    console: Console, lines: Iterable[str], out: TextIO, err: TextIO, source: str
) -> int:
    """Run a script; the first error stops it with status 2 and names the line."""
    for number, line in enumerate(lines, start=1):
        if line.strip().lower() in ("quit", "exit"):
            break
        try:
            for text in console.execute(line):
                print(text, file=out)
        except FieldtwinError as exc:
            out.flush()
            print(f"{source}:{number}: {line.strip()}: {exc}", file=err)
            return 2
    return 0


__all__ = ["HELP", "Console", "parse_duration", "run_script"]
