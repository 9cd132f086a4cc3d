"""A scenario run on a plant: each step at its simulated instant, through the door.

``ScenarioRun(plant, scenario, call=..., line=...).start()`` schedules every step
and expectation on the plant's clock, relative to the simulated time it starts
at.  A step is a command value through the plant's door (fieldtwin.runtime.door),
the control API's (``set_input``, ``set_fault``, ``power_cycle``...) or a console
line (``write W100 30``): the same path as the API, so a recording sees it.  Where
the door serves nothing for a kind (a plant in a test, no control API), the run
uses the handlers it was given.  An expectation reads its value without side
effect; the result names, for the first that failed, the table, the object, the
expected and actual values and the simulated time (docs/scenarios.md).
"""

from __future__ import annotations

import functools
import importlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from fieldtwin.clock import Handle, S, seconds
from fieldtwin.devices.face import Device, device_id
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.plant import Plant
from fieldtwin.runtime.door import CALL, LINE, Command, Handler
from fieldtwin.scenario.spec import Expect, Scalar, Scenario, Step

STEP_PRIORITY = 0  # a step runs with the plant's other events of its instant
EXPECT_PRIORITY = (1 << 30) - 2  # an expectation reads after them (and before a mode ends)
END_PRIORITY = (1 << 30) - 1
MAX_VALUE_TEXT = 200


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one step or expectation gave: ``ok``, and the words that say it."""

    kind: str  # "step" or "expect"
    index: int
    at_s: float  # as written (after the scenario's start)
    t_s: float  # the plant's simulated time
    ok: bool
    what: str  # the step, or the object read
    expected: str = ""
    actual: str = ""
    message: str = ""

    def json(self) -> dict[str, object]:
        return {
            "kind": self.kind,
            "index": self.index,
            "at_s": self.at_s,
            "t_s": self.t_s,
            "ok": self.ok,
            "what": self.what,
            "expected": self.expected,
            "actual": self.actual,
            "message": self.message,
        }


@dataclass(slots=True)
class ScenarioResult:
    """Every outcome so far, and whether the run has ended."""

    name: str
    title: str
    started_s: float
    end_s: float
    outcomes: list[Outcome] = field(default_factory=list)
    done: bool = False

    @property
    def passed(self) -> bool:
        return self.done and all(o.ok for o in self.outcomes)

    @property
    def failures(self) -> list[Outcome]:
        return [o for o in self.outcomes if not o.ok]

    def summary(self) -> str:
        """One line: passed, or the first failure's message."""
        failed = self.failures
        if failed:
            return f"scenario {self.name}: FAILED: {failed[0].message}"
        held = sum(1 for o in self.outcomes if o.kind == "expect")
        steps = sum(1 for o in self.outcomes if o.kind == "step")
        if not self.done:
            return f"scenario {self.name}: running ({steps} steps, {held} expectations so far)"
        return (
            f"scenario {self.name}: passed ({steps} steps, {held} expectations held,"
            f" ended at t = {self.started_s + self.end_s:.3f} s)"
        )

    def lines(self) -> list[str]:
        """One line per outcome, then the summary (the console's and the CLI's report)."""
        out = [
            f"ok   t = {o.t_s:.3f} s  {o.kind}[{o.index}]  {o.what}"
            if o.ok
            else f"FAIL {o.message}"
            for o in self.outcomes
        ]
        return [*out, self.summary()]

    def json(self) -> dict[str, object]:
        failed = self.failures
        return {
            "name": self.name,
            "title": self.title,
            "started_s": self.started_s,
            "end_s": self.end_s,
            "done": self.done,
            "passed": self.passed,
            "failure": failed[0].message if failed else None,
            "outcomes": [o.json() for o in self.outcomes],
        }


def _text(value: object) -> str:
    """A value as a report shows it: true/false, numbers, texts quoted."""
    if isinstance(value, bool):
        return "true" if value else "false"
    text = repr(value) if isinstance(value, str) else str(value)
    if isinstance(value, float):
        text = f"{value:.6g}"
    return text[:MAX_VALUE_TEXT]


class ScenarioRun:
    """One scenario on one plant (see the module docstring)."""

    def __init__(
        self,
        plant: Plant,
        scenario: Scenario,
        *,
        call: Handler | None = None,
        line: Handler | None = None,
        on_end: Callable[[ScenarioResult], None] | None = None,
    ) -> None:
        self.plant = plant
        self.scenario = scenario
        self._fallback = {CALL: call, LINE: line}
        self.on_end = on_end
        self.result = ScenarioResult(scenario.name, scenario.title, 0.0, scenario.end_s)
        self._handles: list[Handle] = []
        self._start_us = 0
        self._last_step: Step | None = None  # the last step run, and when (s)
        self._last_step_t = 0.0
        self.check()

    # --- before it starts: every name it uses exists ----------------------------------

    def _devices(self) -> dict[str, Device]:
        devices = self.plant.devices
        return {device_id(d, devices): d for d in devices}

    def _device(self, ident: str, where: str) -> Device:
        found = self._devices()
        device = found.get(ident)
        if device is None:
            raise ConfigError(f"{where}: no device {ident!r} (allowed: {', '.join(found)})")
        return device

    def check(self) -> None:
        """Every device, module, object and tag the scenario names exists on this plant
        (ConfigError naming the table and field); the values are read at run time."""
        plc = self.plant.plc
        for step in self.scenario.steps:
            args, where = step.args, f"{step.where}.{step.action}"
            device = args.get("device")
            if isinstance(device, str) and not (step.action == "power_off" and device == "plc"):
                self._device(device, f"{where}.device")
            if step.action == "power_off" and device == "plc" and plc is None:
                raise ConfigError(f"{where}.device: 'plc' but this plant has no PLC")
            needs_plc = step.action in ("remove", "insert", "exchange") or "object" in args
            if needs_plc and plc is None:
                raise ConfigError(f"{where}: this plant has no PLC")
        for expect in self.scenario.expects:
            where = expect.where
            try:
                self._read(expect)
            except ConfigError as exc:
                raise ConfigError(f"{where}.{expect.kind}: {exc}") from None

    # --- running -----------------------------------------------------------------------

    def start(self) -> ScenarioRun:
        """Schedule every step and expectation from now on the plant's clock."""
        clock = self.plant.clock
        self._start_us = clock.now
        self.result.started_s = clock.now / S
        for step in self.scenario.steps:
            self._at(step.at_s, functools.partial(self._step, step), STEP_PRIORITY)
        for expect in self.scenario.expects:
            self._at(expect.at_s, functools.partial(self._expect, expect), EXPECT_PRIORITY)
        self._at(self.scenario.end_s, self._end, END_PRIORITY)
        return self

    def _at(self, at_s: float, callback: Callable[[int], None], priority: int) -> None:
        clock = self.plant.clock
        self._handles.append(clock.schedule(self._start_us + seconds(at_s), callback, priority))

    def cancel(self) -> None:
        """Stop here: what has not run yet never runs (the result stays not done)."""
        for handle in self._handles:
            handle.cancel()
        self._handles.clear()

    @property
    def end_us(self) -> int:
        """The simulated time (µs) it ends at."""
        return self._start_us + seconds(self.scenario.end_s)

    def _now_s(self) -> float:
        return self.plant.clock.now / S

    def _dispatch(self, command: Command) -> object:
        door = self.plant.door
        handler: Handler | None = None
        try:
            door.handler(command.kind)
        except ConfigError:
            handler = self._fallback[command.kind]
            if handler is None:
                raise
        return door.dispatch(command, handler)

    def _command(self, step: Step) -> Command:
        a = step.args
        action = step.action
        if action == "input":
            return Command.call("set_input", a["device"], a["name"], a["value"], None)
        if action == "signal":
            table = {k: v for k, v in a.items() if k not in ("device", "name")}
            return Command.call("set_input", a["device"], a["name"], None, table)
        if action == "fault":
            return Command.call("set_fault", a["device"], a["name"], a["active"], a["params"])
        if action == "power_off":
            if a["device"] == "plc":
                return Command.call("power_break", a["seconds"])
            return Command.call("power_cycle", a["device"], a["seconds"])
        if action == "write":
            if "object" in a:
                return Command.line(f"write {a['object']} {a['value']}")
            return Command.call("write_object", a["device"], a["register"], a["value"])
        if action in ("remove", "insert"):
            return Command.call(action, a["module"])
        if action == "exchange":
            return Command.call(
                "start_exchange",
                a["m"],
                a["c"],
                a["send"],
                a.get("text"),
                a["length"],
                a["recv"],
                a["txt"],
            )
        return Command.line(str(a["line"]))

    def _step(self, step: Step, now: int) -> None:
        self._last_step, self._last_step_t = step, now / S
        try:
            self._dispatch(self._command(step))
        except FieldtwinError as exc:
            message = f"step[{step.index}] {step.text()} at t = {self._now_s():.3f} s failed: {exc}"
            self._add(
                Outcome(
                    "step",
                    step.index,
                    step.at_s,
                    self._now_s(),
                    False,
                    step.text(),
                    message=message,
                )
            )
            return
        self._add(Outcome("step", step.index, step.at_s, self._now_s(), True, step.text()))

    def _expect(self, expect: Expect, now_us: int) -> None:
        now = self._now_s()
        try:
            value: object = self._read(expect)
        except FieldtwinError as exc:
            value, error = None, str(exc)
        else:
            error = ""
        ok = not error and _holds(expect, value)
        actual = error or _text(value)
        after, after_t = self._last_step, self._last_step_t
        context = (
            f" (after step[{after.index}] {after.text()} at t = {after_t:.3f} s)"
            if after is not None
            else ""
        )
        message = (
            f"expect[{expect.index}] at t = {now:.3f} s: {expect.text()} expected"
            f" {expect.expected_text()}, actual {actual}{context}"
        )
        self._add(
            Outcome(
                "expect",
                expect.index,
                expect.at_s,
                now,
                ok,
                expect.text(),
                expect.expected_text(),
                actual,
                "" if ok else message,
            )
        )

    def _add(self, outcome: Outcome) -> None:
        self.result.outcomes.append(outcome)

    def _end(self, now: int) -> None:
        self.result.done = True
        self._handles.clear()
        if self.on_end is not None:
            self.on_end(self.result)

    # --- reading, without side effect -----------------------------------------------------

    def _read(self, expect: Expect) -> object:
        if expect.kind == "tag":
            return tag_value(self.plant, expect.name)
        if expect.kind == "object":
            plc = self.plant.plc
            if plc is None:
                raise ConfigError("this plant has no PLC (name a device's register instead)")
            return object_value(plc.read, plc.read_signed, expect.name)
        assert expect.device is not None
        device = self._device(expect.device, "device")
        if expect.kind == "register":
            return device.objects().peek(expect.name)
        if expect.kind == "output":
            outputs = device.outputs()
            if expect.name not in outputs:
                raise ConfigError(
                    f"{expect.device} has no output {expect.name!r}"
                    f" (allowed: {', '.join(outputs) or 'none'})"
                )
            return outputs[expect.name].read().value
        if expect.kind == "led":
            leds = dict(device.status().leds)
            if expect.name not in leds:
                raise ConfigError(
                    f"{expect.device} has no LED {expect.name!r} (allowed: {', '.join(leds)})"
                )
            return str(leds[expect.name])
        return input_value(device, expect.name)


def object_value(read: Callable[[str], int], read_signed: Callable[[str], int], name: str) -> int:
    """A PL7 object: a bit 0 or 1, a word signed (-32768..32767) as PL7 reads it."""
    value = read(name)
    head = name.strip().upper()
    if head.startswith(("I", "O", "B", "SY")) and not head.startswith(("IW", "OW")):
        return value
    if head.count(",") == 2:  # IW5,0,4: a bit of a word
        return value
    try:
        return read_signed(name)
    except ConfigError:
        return value


def input_value(device: Device, name: str) -> object:
    """An input as the device's front shows it: a measurement in its unit, or a contact."""
    inputs = device.inputs()
    if name not in inputs:
        raise ConfigError(f"no input {name!r} (allowed: {', '.join(list(inputs)[:40]) or 'none'})")
    panel = device.panel()
    for reading in panel.readings:
        if reading.name == name:
            return reading.value
    row = panel.row("in")
    if name.isdigit() and int(name) < len(row):
        return row[int(name)]
    raise ConfigError(f"input {name!r} is not shown on the device's front (read its object)")


def tag_value(plant: Plant, name: str) -> object:
    """A tag's value in its unit (the plant's [[tag]] tables: fieldtwin.plant.tags)."""
    try:
        tags = importlib.import_module("fieldtwin.plant.tags")
    except ImportError:
        raise ConfigError(f"tag {name!r}: this fieldtwin has no plant tags") from None
    return tags.read_value(plant, name).value


def _holds(expect: Expect, value: object) -> bool:
    if expect.between is not None:
        if not isinstance(value, int | float):  # a bit or a contact counts 0 or 1
            return False
        low, high = expect.between
        return low <= value <= high
    return equal(expect.equals, value)


def equal(expected: Scalar | None, value: object) -> bool:
    """``equals``: numbers by value (true is 1), texts without case (an LED ``on``)."""
    if isinstance(expected, str) or isinstance(value, str):
        return str(expected).strip().lower() == str(value).strip().lower()
    if isinstance(value, int | float) and isinstance(expected, int | float):
        return math.isclose(float(value), float(expected), rel_tol=1e-9, abs_tol=1e-9)
    return False


__all__ = [
    "Outcome",
    "ScenarioResult",
    "ScenarioRun",
    "equal",
    "input_value",
    "object_value",
    "tag_value",
]
