"""A scenario file, read and checked (docs/scenarios.md).

A TOML file of ``[[step]]`` tables (``at_s`` and one action) and ``[[expect]]``
tables (``at_s``, what is read, ``equals`` or ``between``).  Every mistake is a
ConfigError naming the file, the table (``step[3]``, counted from 1) and the
field, and what is allowed; nothing unbounded: at most MAX_ENTRIES tables, times
within MAX_AT_S, a file of at most MAX_FILE_BYTES.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from fieldtwin.errors import ConfigError, refuse_unknown_keys

MAX_ENTRIES = 10_000  # [[step]] and [[expect]] tables together
MAX_AT_S = 366 * 24 * 3600.0  # a simulated year, as run_until's bound
MAX_FILE_BYTES = 1_000_000
MAX_OUTAGE_S = 3600.0  # power_off seconds (a TES's outage, the PLC's power break)

# The actions of a [[step]], each with its keys (required, optional).
ACTIONS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "input": (("device", "name", "value"), ()),
    "signal": (("device", "name", "kind"), ()),  # and the signal's own keys
    "fault": (("device", "name"), ("active", "params")),
    "power_off": (("device", "seconds"), ()),
    "write": (("value",), ("object", "device", "register")),
    "remove": (("module",), ()),
    "insert": (("module",), ()),
    "exchange": (("m", "c"), ("send", "text", "length", "recv", "txt")),
    "console": ((), ()),  # a console line (a string)
}
# What an [[expect]] reads: one of these (device with one of DEVICE_READS).
TARGETS = ("tag", "object", "device")
DEVICE_READS = ("input", "output", "register", "led")
EXPECT_KEYS = ("at_s", *TARGETS, *DEVICE_READS, "equals", "between")
TOP_KEYS = ("title", "description", "step", "expect")

Scalar = bool | int | float | str


@dataclass(frozen=True, slots=True)
class Step:
    """One ``[[step]]``: at ``at_s``, the action ``action`` with its table ``args``."""

    index: int  # from 1, in file order
    at_s: float
    action: str
    args: Mapping[str, object]
    where: str  # "FILE: step[3]"

    def text(self) -> str:
        """``fault 5 open_3 on``, ``power_off tes2 2 s``: as a report names the step."""
        a = self.args
        if self.action == "console":
            return f"console {a['line']!r}"
        if self.action == "fault":
            state = "on" if a.get("active", True) else "off"
            return f"fault {a['device']} {a['name']} {state}"
        if self.action == "power_off":
            return f"power_off {a['device']} {a['seconds']:g} s"
        if self.action == "write":
            target = a.get("object") or f"{a['device']} {a['register']}"
            return f"write {target} = {a['value']!r}"
        if self.action in ("remove", "insert"):
            return f"{self.action} {a['module']}"
        if self.action == "exchange":
            return f"exchange M={a['m']} C={a['c']}"
        if self.action == "signal":
            return f"signal {a['device']} {a['name']} {a['kind']}"
        value = a["value"]
        shown = ("true" if value else "false") if isinstance(value, bool) else repr(value)
        return f"{self.action} {a['device']} {a['name']} = {shown}"


@dataclass(frozen=True, slots=True)
class Expect:
    """One ``[[expect]]``: at ``at_s``, ``target`` reads ``equals`` or within ``between``."""

    index: int
    at_s: float
    kind: str  # tag, object, input, output, register, led
    name: str  # the tag, the object, or the device's input/output/register/LED
    device: str | None
    equals: Scalar | None
    between: tuple[float, float] | None
    where: str

    def text(self) -> str:
        """``IW5,0,4``, ``tes2 register 0x000``, ``tag tank1.level``, ``5 LED ERR``."""
        if self.kind == "object":
            return self.name
        if self.kind == "tag":
            return f"tag {self.name}"
        if self.kind == "led":
            return f"{self.device} LED {self.name}"
        return f"{self.device} {self.kind} {self.name}"

    def expected_text(self) -> str:
        if self.between is not None:
            low, high = self.between
            return f"between {low:g} and {high:g}"
        if isinstance(self.equals, bool):
            return "true" if self.equals else "false"
        return repr(self.equals)


@dataclass(frozen=True, slots=True)
class Scenario:
    """A scenario: its steps and expectations, in time order (file order at one time)."""

    name: str  # the file's name
    title: str = ""
    description: str = ""
    steps: tuple[Step, ...] = field(default_factory=tuple)
    expects: tuple[Expect, ...] = field(default_factory=tuple)

    @property
    def end_s(self) -> float:
        """The time of its last step or expectation (0 when it has none)."""
        times = [s.at_s for s in self.steps] + [e.at_s for e in self.expects]
        return max(times, default=0.0)


def read_scenario(path: str | Path) -> Scenario:
    """The scenario in ``path``; ConfigError naming the file and what is wrong."""
    file = Path(path)
    try:
        with file.open("rb") as stream:
            data = stream.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{file}: cannot read the scenario file ({exc.strerror})") from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(f"{file}: larger than {MAX_FILE_BYTES} bytes (a scenario file)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{file}: not UTF-8 text (a TOML scenario file)") from None
    return parse_scenario(text, file.name)


def parse_scenario(text: str, name: str = "scenario") -> Scenario:
    """The scenario written in ``text`` (TOML); ``name`` is what errors call it."""
    if len(text) > MAX_FILE_BYTES:
        raise ConfigError(f"{name}: larger than {MAX_FILE_BYTES} characters (a scenario)")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{name}: not valid TOML ({exc})") from None
    return scenario_of(data, name)


def scenario_of(data: Mapping[str, object], name: str = "scenario") -> Scenario:
    """A scenario from its tables (as TOML or JSON gives them)."""
    refuse_unknown_keys(data, TOP_KEYS, name)
    steps_in = _tables(data.get("step", []), f"{name}: step")
    expects_in = _tables(data.get("expect", []), f"{name}: expect")
    if not steps_in and not expects_in:
        raise ConfigError(f"{name}: no [[step]] and no [[expect]] table (a scenario needs one)")
    if len(steps_in) + len(expects_in) > MAX_ENTRIES:
        raise ConfigError(
            f"{name}: {len(steps_in) + len(expects_in)} [[step]] and [[expect]] tables"
            f" (allowed at most {MAX_ENTRIES})"
        )
    steps = [_step(t, i, f"{name}: step[{i}]") for i, t in enumerate(steps_in, 1)]
    expects = [_expect(t, i, f"{name}: expect[{i}]") for i, t in enumerate(expects_in, 1)]
    return Scenario(
        name=name,
        title=_text(data.get("title", ""), f"{name}: title"),
        description=_text(data.get("description", ""), f"{name}: description"),
        steps=tuple(sorted(steps, key=lambda s: s.at_s)),
        expects=tuple(sorted(expects, key=lambda e: e.at_s)),
    )


def _tables(value: object, where: str) -> list[Mapping[str, object]]:
    if not isinstance(value, list) or not all(isinstance(t, Mapping) for t in value):
        raise ConfigError(f"{where}: an array of tables ([[{where.rpartition(' ')[2]}]])")
    return list(value)


def _text(value: object, where: str, limit: int = 4000) -> str:
    if not isinstance(value, str) or len(value) > limit:
        raise ConfigError(f"{where}: a string of at most {limit} characters")
    return value


def _name(value: object, where: str) -> str:
    if isinstance(value, int) and not isinstance(value, bool):
        value = str(value)  # device = 5, module = 5, name = 3
    if not isinstance(value, str) or not value.strip() or len(value) > 64:
        raise ConfigError(f'{where}: {value!r} not allowed (allowed: a name, e.g. "5", "tes1")')
    return value.strip()


def number(value: object, where: str, low: float = -math.inf, high: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{where}: {value!r} not allowed (allowed: a number)")
    if not low <= value <= high:
        raise ConfigError(f"{where}: {value!r} not allowed (allowed: {low:g} to {high:g})")
    return float(value)


def _at(table: Mapping[str, object], where: str) -> float:
    if "at_s" not in table:
        raise ConfigError(f"{where}: at_s missing (the simulated second it happens at)")
    return number(table["at_s"], f"{where}.at_s", 0.0, MAX_AT_S)


def _step(table: Mapping[str, object], index: int, where: str) -> Step:
    at_s = _at(table, where)
    actions = [k for k in table if k != "at_s"]
    unknown = [k for k in actions if k not in ACTIONS]
    if unknown:
        raise ConfigError(
            f"{where}: unknown key(s) {', '.join(unknown)} (allowed: at_s and one action of"
            f" {', '.join(ACTIONS)})"
        )
    if len(actions) != 1:
        raise ConfigError(
            f"{where}: {'no action' if not actions else 'actions ' + ', '.join(actions)}"
            f" (allowed: exactly one of {', '.join(ACTIONS)})"
        )
    action = actions[0]
    return Step(index, at_s, action, _args(action, table[action], f"{where}.{action}"), where)


def _args(action: str, value: object, where: str) -> dict[str, object]:
    if action == "console":
        return {"line": _text(value, where, 1000)}
    if not isinstance(value, Mapping):
        raise ConfigError(f'{where}: a table, e.g. {action} = {{ device = "5", ... }}')
    required, optional = ACTIONS[action]
    missing = [k for k in required if k not in value]
    if missing:
        raise ConfigError(f"{where}: {', '.join(missing)} missing (takes {_takes(action)})")
    if action != "signal":
        unknown = sorted(set(value) - set(required) - set(optional))
        if unknown:
            raise ConfigError(
                f"{where}: unknown key(s) {', '.join(unknown)} (takes {_takes(action)})"
            )
    args: dict[str, object] = dict(value)
    for key in ("device", "module"):
        if key in args:
            args[key] = _name(args[key], f"{where}.{key}").lower()
    if "name" in args:
        args["name"] = _name(args["name"], f"{where}.name")
    if action == "input" and not isinstance(args["value"], bool | int | float | str):
        raise ConfigError(f'{where}.value: a number, true/false, or a text such as "12mA"')
    if action == "fault":
        active = args.setdefault("active", True)
        if not isinstance(active, bool):
            raise ConfigError(f"{where}.active: {active!r} not allowed (allowed: true, false)")
        params = args.setdefault("params", {})
        if not isinstance(params, Mapping) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in params.values()
        ):
            raise ConfigError(f"{where}.params: a table of numbers, e.g. {{ ms = 200 }}")
        args["params"] = dict(params)
    if action == "power_off":
        args["seconds"] = number(args["seconds"], f"{where}.seconds", 0.0, MAX_OUTAGE_S)
    if action == "write":
        _write_args(args, where)
    if action == "exchange":
        _exchange_args(args, where)
    return args


def _write_args(args: dict[str, object], where: str) -> None:
    has_object = "object" in args
    has_register = "device" in args or "register" in args
    if has_object == has_register or (has_register and not {"device", "register"} <= set(args)):
        raise ConfigError(
            f'{where}: give either object (a PL7 object, e.g. "W100", "OW5,0") or device'
            ' and register (e.g. device = "tes1", register = "0x000")'
        )
    if has_object:
        args["object"] = _name(args["object"], f"{where}.object")
    else:
        args["register"] = _name(args["register"], f"{where}.register")
    value = args["value"]
    if isinstance(value, bool) or not isinstance(value, int) or not -32768 <= value <= 0xFFFF:
        raise ConfigError(f"{where}.value: {value!r} not allowed (allowed: a word, -32768..65535)")


def _exchange_args(args: dict[str, object], where: str) -> None:
    for key in ("m", "c"):
        value = args[key]
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFFFF:
            raise ConfigError(f"{where}.{key}: {value!r} not allowed (allowed: 0..65535)")
    send = args.setdefault("send", [])
    if (
        not isinstance(send, list)
        or len(send) > 256
        or not all(
            isinstance(w, int) and not isinstance(w, bool) and 0 <= w <= 0xFFFF for w in send
        )
    ):
        raise ConfigError(f"{where}.send: a list of at most 256 words (0..65535)")
    if "text" in args:
        args["text"] = _text(args["text"], f"{where}.text", 512)
    for key, default, high in (("length", None, 512), ("recv", 0, 512), ("txt", 0, 63)):
        value = args.get(key, default)
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= high
        ):
            raise ConfigError(f"{where}.{key}: {value!r} not allowed (allowed: 0..{high})")
        args[key] = value


def _takes(action: str) -> str:
    required, optional = ACTIONS[action]
    words = [*required, *(f"[{k}]" for k in optional)]
    if action == "signal":
        words.append("and the signal's keys (docs/signals.md)")
    return ", ".join(words)


def _expect(table: Mapping[str, object], index: int, where: str) -> Expect:
    at_s = _at(table, where)
    refuse_unknown_keys(table, EXPECT_KEYS, where)
    targets = [k for k in TARGETS if k in table]
    if len(targets) != 1:
        raise ConfigError(
            f"{where}: give one of tag, object, or device with one of"
            f" {', '.join(DEVICE_READS)} (found: {', '.join(targets) or 'none'})"
        )
    device: str | None = None
    reads = [k for k in DEVICE_READS if k in table]
    if targets[0] == "device":
        device = _name(table["device"], f"{where}.device").lower()
        if len(reads) != 1:
            raise ConfigError(
                f"{where}: with device, give one of {', '.join(DEVICE_READS)}"
                f" (found: {', '.join(reads) or 'none'})"
            )
        kind = reads[0]
    else:
        if reads:
            raise ConfigError(f"{where}.{reads[0]}: goes with device, not with {targets[0]}")
        kind = targets[0]
    target = _name(table[kind], f"{where}.{kind}")
    if ("equals" in table) == ("between" in table):
        raise ConfigError(f"{where}: give either equals or between = [low, high]")
    equals: Scalar | None = None
    between: tuple[float, float] | None = None
    if "equals" in table:
        value = table["equals"]
        if not isinstance(value, bool | int | float | str) or (
            isinstance(value, float) and not math.isfinite(value)
        ):
            raise ConfigError(f'{where}.equals: a number, true/false, or a text such as "on"')
        equals = value
    else:
        pair = table["between"]
        if not isinstance(pair, list) or len(pair) != 2:
            raise ConfigError(f"{where}.between: [low, high], two numbers")
        low = number(pair[0], f"{where}.between[0]")
        high = number(pair[1], f"{where}.between[1]")
        if low > high:
            raise ConfigError(f"{where}.between: low {low:g} above high {high:g}")
        between = (low, high)
    if kind == "led" and not isinstance(equals, str):
        raise ConfigError(f'{where}.equals: an LED\'s state, e.g. "on", "off", "blink"')
    return Expect(index, at_s, kind, target, device, equals, between, where)


__all__ = [
    "ACTIONS",
    "DEVICE_READS",
    "MAX_AT_S",
    "MAX_ENTRIES",
    "MAX_FILE_BYTES",
    "MAX_OUTAGE_S",
    "Expect",
    "Scenario",
    "Step",
    "number",
    "parse_scenario",
    "read_scenario",
    "scenario_of",
]
