"""The programming terminal of the twin: `fieldtwin console [PLANT]`.

Every command returns its output lines; the formats are stable and documented
in docs/console.md (e.g. ``IW5,0 = H'1008'``).  An error is a ConfigError whose
message names the token at fault and what is allowed.
"""

from __future__ import annotations

import shlex
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TextIO

from fieldtwin.clock import S
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.plant import Plant
from fieldtwin.signals import signal_from_spec
from fieldtwin.tsx.addressing import format_object, parse_module, parse_object
from fieldtwin.tsx.plc import Plc
from fieldtwin.words import format_hex, parse_word

HELP = {
    "read": "read OBJECT...            IW5,0  OW5,0,C  I5,3  I5,S  W100"
    " (a name alone reads it too)",
    "write": "write OBJECT VALUE        OW5,0,C 1   OW5,1 H'00FF'   O5,2 1   W100 30",
    "exchange": 'exchange M C [send W...] [text "..."] [length L] [recv N] [txt I] [timeout S]\n'
    "                           e.g. exchange H'0563' H'40' send H'00A0' 30 recv 0",
    "advance": "advance DURATION          advance 11   advance 250ms   advance 2min",
    "time": "time                      the simulated time",
    "status": "status [MODULE]           module state, mode, LEDs, registers (MODULE = 5 or 23)",
    "input": "input MODULE CHANNEL VALUE   set an input as the module takes it"
    " (2.5V, 12mA, open, 1)",
    "signal": "signal MODULE CHANNEL KIND key=value...\n"
    "                           e.g. signal 5 0 sine offset=5 amplitude=2 period_s=60",
    "fault": "fault MODULE NAME on|off  inject or clear a fault; 'faults MODULE' lists the names",
    "faults": "faults MODULE             the faults a module can be given",
    "power": "power break SECONDS       cut the PLC supply",
    "remove": "remove MODULE             pull a module out under power",
    "insert": "insert MODULE             put it back (it runs its self-test)",
    "plc": "plc run|stop|cold|hot     PLC mode, cold restart (SY0), hot restart (SY1)",
    "tes": "tes SLAVE read ADDR [N] | write ADDR VALUE | input I VALUE | power-cycle",
    "help": "help [COMMAND]",
    "quit": "quit",
}

_UNITS = {"us": 1e-6, "ms": 1e-3, "s": 1.0, "min": 60.0, "h": 3600.0}


def parse_duration(token: str) -> float:
    """'11', '250ms', '2min', '1.5s' -> seconds."""
    text = token.strip().lower()
    for unit in sorted(_UNITS, key=len, reverse=True):
        if text.endswith(unit):
            number, factor = text[: -len(unit)], _UNITS[unit]
            break
    else:
        number, factor = text, 1.0
    try:
        value = float(number) * factor
    except ValueError:
        raise ConfigError(f"{token!r} is not a duration (e.g. 11, 1.5s, 250ms, 2min)") from None
    if value < 0:
        raise ConfigError(f"{token!r}: a duration cannot be negative")
    return value


def _value(token: str) -> Any:
    for cast in (int, float):
        try:
            return cast(token)
        except ValueError:
            pass
    if token.lower() in ("true", "false"):
        return token.lower() == "true"
    return token


class Console:
    """Executes console commands against a plant."""

    def __init__(self, plant: Plant) -> None:
        self.plant = plant
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
            "power": self._power,
            "remove": self._remove,
            "insert": self._insert,
            "plc": self._plc_mode,
            "tes": self._tes,
            "help": self._help,
        }

    @property
    def plc(self) -> Plc:
        if self.plant.plc is None:
            raise ConfigError("this plant has no PLC (add a [plc] table or [[module]] tables)")
        return self.plant.plc

    def execute(self, line: str) -> list[str]:
        """Run one command line; returns its output lines."""
        try:
            words = _split(line)
        except ValueError as exc:
            raise ConfigError(f"cannot split {line.strip()!r}: {exc}") from None
        if not words:
            return []
        name, args = words[0].lower(), words[1:]
        if len(words) == 3 and words[1] == "=":  # OW5,0,C = 1
            return self._write([words[0], words[2]])
        command = self._commands.get(name)
        if command is not None:
            return command(args)
        if _looks_like_object(words[0]):
            return self._read(words)
        raise ConfigError(f"unknown command {words[0]!r} (allowed: {', '.join(HELP)})")

    # --- objects -------------------------------------------------------------

    def _read(self, args: list[str]) -> list[str]:
        if not args:
            raise ConfigError("read: name at least one object, e.g. read IW5,0")
        return [f"{_canonical(name)} = {self._show(name)}" for name in args]

    def _show(self, name: str) -> str:
        value = self.plc.read(name)
        if name.upper().startswith("W"):
            return str(value)
        ref = parse_object(name)
        return str(value) if ref.is_bit else format_hex(value)

    def _write(self, args: list[str]) -> list[str]:
        if len(args) != 2:
            raise ConfigError("write: takes OBJECT VALUE, e.g. write OW5,0,C 1")
        name, token = args
        self.plc.write(name, parse_word(token) if not token.startswith("-") else int(token))
        return [f"{_canonical(name)} = {self._show(name)}"]

    # --- Text Blocks -----------------------------------------------------------

    def _exchange(self, args: list[str]) -> list[str]:
        if len(args) < 2:
            raise ConfigError('exchange: takes M C [send W...] [text "..."] [recv N] ...')
        m, c = parse_word(args[0]), parse_word(args[1])
        options: dict[str, Any] = {"recv_bytes": 0}
        send: list[int] = []
        it = iter(args[2:])
        mode = None
        for token in it:
            key = token.lower()
            if key in ("send", "text", "recv", "txt", "timeout", "length"):
                mode = key
                if key != "send":
                    options[key] = _next(it, token)
                continue
            if mode != "send":
                raise ConfigError(
                    f'exchange: unexpected {token!r} (allowed: send W..., text "...", length L,'
                    " recv N, txt I, timeout S)"
                )
            send.append(parse_word(token))
        txt = int(options.pop("txt", 0))
        kwargs: dict[str, Any] = {"recv_bytes": int(options.pop("recv", options["recv_bytes"]))}
        options.pop("recv_bytes")
        if "text" in options:
            kwargs["send_bytes"] = options.pop("text").encode("latin-1")
        else:
            kwargs["send"] = send
        if "length" in options:
            kwargs["length"] = int(options.pop("length"))
        if "timeout" in options:
            kwargs["timeout_s"] = parse_duration(options.pop("timeout"))
        result = self.plc.exchange(m, c, txt=txt, **kwargs)
        name = f"TXT{txt}"
        lines = [
            f"{name},{result.report_name} = {format_hex(result.v)}  {name},S = {result.s}"
            f"  {name},E = {int(result.e)}" + (f"  ({result.error_text})" if result.e else "")
        ]
        if result.data:
            lines.append("data = " + " ".join(format_hex(w) for w in result.words))
            printable = "".join(chr(b) if 32 <= b < 127 else "." for b in result.data)
            lines.append(f"text = {printable!r}")
        return lines

    # --- time ----------------------------------------------------------------------

    def _time(self) -> str:
        return f"t = {self.plant.clock.now / S:.3f} s"

    def _advance(self, args: list[str]) -> list[str]:
        if len(args) != 1:
            raise ConfigError("advance: takes one duration, e.g. advance 11 or advance 250ms")
        duration = parse_duration(args[0])
        if self.plant.plc is not None:
            self.plant.plc.advance(duration)
        else:
            self.plant.clock.advance(round(duration * S))
        return [self._time()]

    # --- modules ---------------------------------------------------------------------

    def _module(self, token: str) -> Any:
        rack, slot = _module_address(token)
        return self.plc.module(rack, slot)

    def _status(self, args: list[str]) -> list[str]:
        plc = self.plc
        modules = [self._module(args[0])] if args else plc.modules
        lines = [f"PLC {plc.model.name} {'RUN' if plc.running else 'STOP'}  {self._time()}"]
        for module in modules:
            lines.append("")
            for key, value in module.status().items():
                lines.append(f"{key}: {value}")
            iw = " ".join(format_hex(w) for w in plc.image(module.rack, module.slot).iw)
            ow = " ".join(format_hex(w) for w in plc.output_words(module.rack, module.slot))
            lines.append(f"IW: {iw}")
            lines.append(f"OW: {ow}")
            lines.append(f"I: {plc.image(module.rack, module.slot).i_bits:016b} (F..0)")
        return lines

    def _input(self, args: list[str]) -> list[str]:
        if len(args) != 3:
            raise ConfigError("input: takes MODULE CHANNEL VALUE, e.g. input 5 0 2.5V")
        module = self._module(args[0])
        module.console_input(_channel(args[1]), args[2])
        return [f"input {module.address} {args[1]} = {args[2]}"]

    def _signal(self, args: list[str]) -> list[str]:
        if len(args) < 3:
            raise ConfigError(
                "signal: takes MODULE CHANNEL KIND key=value..., e.g. signal 5 0 sine"
            )
        module = self._module(args[0])
        spec: dict[str, Any] = {"kind": args[2]}
        for pair in args[3:]:
            key, sep, value = pair.partition("=")
            if not sep:
                raise ConfigError(f"signal: {pair!r} is not key=value")
            spec[key] = _value(value)
        where = f"signal {args[0]} {args[1]}"
        built = signal_from_spec(spec, where=where)
        try:
            module.set_signal(_channel(args[1]), built)
        except TypeError:
            raise ConfigError(
                f"{module.type_name} takes no input signals (see its page for 'input')"
            ) from None
        return [f"signal {module.address} {args[1]} = {args[2]}"]

    def _fault(self, args: list[str]) -> list[str]:
        if len(args) != 3 or args[2].lower() not in ("on", "off"):
            raise ConfigError("fault: takes MODULE NAME on|off, e.g. fault 5 terminal_block on")
        module = self._module(args[0])
        module.inject_fault(args[1], args[2].lower() == "on")
        return [f"fault {module.address} {args[1]} {args[2].lower()}"]

    def _faults(self, args: list[str]) -> list[str]:
        if len(args) != 1:
            raise ConfigError("faults: takes MODULE")
        names = self._module(args[0]).fault_names()
        return [f"{name}: {text}" for name, text in names.items()] or ["(none)"]

    def _power(self, args: list[str]) -> list[str]:
        if len(args) != 2 or args[0] != "break":
            raise ConfigError("power: takes 'break SECONDS', e.g. power break 2")
        self.plc.power_break(parse_duration(args[1]))
        return [f"power back  {self._time()}"]

    def _remove(self, args: list[str]) -> list[str]:
        rack, slot = _module_address(_one(args, "remove MODULE"))
        self.plc.remove(rack, slot)
        return [f"module rack {rack} slot {slot} removed"]

    def _insert(self, args: list[str]) -> list[str]:
        rack, slot = _module_address(_one(args, "insert MODULE"))
        self.plc.reinsert(rack, slot)
        return [f"module rack {rack} slot {slot} inserted"]

    def _plc_mode(self, args: list[str]) -> list[str]:
        actions = {
            "run": self.plc.start,
            "stop": self.plc.stop,
            "cold": self.plc.cold_restart,
            "hot": self.plc.hot_restart,
        }
        mode = _one(args, "plc run|stop|cold|hot").lower()
        if mode not in actions:
            raise ConfigError(f"plc: {mode!r} not allowed (allowed: run, stop, cold, hot)")
        actions[mode]()
        return [f"PLC {'RUN' if self.plc.running else 'STOP'}"]

    # --- TES -------------------------------------------------------------------------

    def _tes(self, args: list[str]) -> list[str]:
        if len(args) < 2:
            raise ConfigError(HELP["tes"])
        try:
            slave = int(args[0])
        except ValueError:
            raise ConfigError(f"tes: {args[0]!r} is not a slave number") from None
        tes, verb, rest = self.plant.tes_by_slave(slave), args[1].lower(), args[2:]
        if verb == "read" and rest:
            start = parse_word(rest[0])
            count = int(rest[1]) if len(rest) > 1 else 1
            return [
                f"tes {slave} {format_hex(a, 3)} = {format_hex(tes.read(a))}"
                for a in range(start, start + count)
            ]
        if verb == "write" and len(rest) == 2:
            address, value = parse_word(rest[0]), parse_word(rest[1])
            tes.write(address, value)
            return [f"tes {slave} {format_hex(address, 3)} = {format_hex(tes.read(address))}"]
        if verb == "input" and len(rest) == 2:
            tes.set_input(int(rest[0]), _value(rest[1]))
            return [f"tes {slave} input {rest[0]} = {rest[1]}"]
        if verb == "power-cycle" and not rest:
            tes.power_cycle()
            return [f"tes {slave} power cycled"]
        raise ConfigError(f"tes: {' '.join(args[1:])!r} not understood ({HELP['tes']})")

    def _help(self, args: list[str]) -> list[str]:
        if args:
            key = args[0].lower()
            if key not in HELP:
                raise ConfigError(f"help: unknown command {args[0]!r} (allowed: {', '.join(HELP)})")
            return [HELP[key]]
        return list(HELP.values())


def _split(line: str) -> list[str]:
    """Words, "quoted text" and # comments; H'00A0' keeps its apostrophes."""
    lexer = shlex.shlex(line, posix=True)
    lexer.quotes = '"'
    lexer.whitespace_split = True
    lexer.commenters = "#"
    return list(lexer)


def _next(it: Iterator[str], token: str) -> str:
    try:
        return next(it)
    except StopIteration:
        raise ConfigError(f"exchange: {token!r} needs a value") from None


def _one(args: list[str], usage: str) -> str:
    if len(args) != 1:
        raise ConfigError(f"takes one argument: {usage}")
    return args[0]


def _channel(token: str) -> int:
    try:
        return int(token, 0)
    except ValueError:
        raise ConfigError(f"{token!r} is not a channel number") from None


def _module_address(token: str) -> tuple[int, int]:
    """'5' -> rack 0 slot 5; '23' -> rack 2 slot 3."""
    return parse_module(token)


def _looks_like_object(token: str) -> bool:
    head = token.upper()
    return head.startswith(("IW", "OW", "I", "O", "W")) and any(ch.isdigit() for ch in head)


def _canonical(name: str) -> str:
    if name.upper().startswith("W"):
        return name.upper()
    return format_object(parse_object(name))


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
