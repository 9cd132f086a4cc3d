"""What the control API does to the plant, through the Device face only.

Every public method here runs on the simulation's thread (the web handlers hand
them to the runner through ``Sim.call``) and returns plain JSON values.  A
user's mistake raises ConfigError (answered 400, or 404 for an unknown device
or Text Block exchange) and changes nothing.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass

from fieldtwin.clock import MS, S
from fieldtwin.clock import seconds as to_us
from fieldtwin.console import Console
from fieldtwin.console_syntax import module_address
from fieldtwin.control.snapshot import Snapshot
from fieldtwin.control.trends import Trends
from fieldtwin.devices.face import (
    Device,
    DeviceStatus,
    Family,
    Fault,
    FaultNotApplicable,
    Input,
    OutputValue,
    device_id,
)
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.plant import Plant, outage
from fieldtwin.runtime.door import Command
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.runner import Runner
from fieldtwin.signals.spec import file_in_spec
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.txt import TextBlock
from fieldtwin.words import format_hex

Json = dict[str, object]
MAX_EXCHANGES = 256  # Text Block exchanges remembered for polling (oldest forgotten first)


class NotFound(ConfigError):
    """An unknown device, input, fault or exchange: answered 404."""


class Conflict(ConfigError):
    """A request that fits its schema but not the plant's state: answered 409 (a time
    already past, a Text Block busy or refusing its table)."""


@dataclass(frozen=True, slots=True)
class _Started:
    id: int
    block: TextBlock
    m: int
    c: int


def status_json(status: DeviceStatus) -> Json:
    return {
        "kind": status.kind,
        "address": status.address,
        "state": status.state,
        "mode": status.mode,
        "leds": dict(status.leds),
        "ports": [{"name": p.name, "line": p.line} for p in status.ports],
        "details": dict(status.details),
        "active_faults": {f.name: dict(f.params) for f in status.active_faults},
        "outputs": [output_json(o) for o in status.outputs],
    }


def output_json(value: OutputValue, description: str | None = None) -> Json:
    """One output: its value in the device's units (a bit: true/false), the raw word."""
    out: Json = {"name": value.name}
    if description is not None:
        out["description"] = description
    out.update({"value": value.value, "unit": value.unit, "raw": value.raw, "text": value.text()})
    return out


def fault_json(fault: Fault) -> Json:
    """A fault: whether it is in force and with which parameters; what it takes."""
    params = fault.in_force()
    return {
        "name": fault.name,
        "description": fault.description,
        "active": params is not None,
        "params": dict(params or {}),
        "takes": list(fault.params),
        "hint": fault.hint(),
    }


def refuse_files(spec: object, where: str) -> None:
    """No request reads a file (docs/control.md, "Security"): a signal table with a
    csv kind or a key naming a file, at any depth, is refused before it is built."""
    found = file_in_spec(spec, where)
    if found is not None:
        raise ConfigError(
            f"{found} reads a file and is not allowed from the control API"
            " (put it in the plant file; allowed here: every other kind of docs/signals.md)"
        )


class _Stale:
    """A door observer: the snapshot is stale after every command (read-your-writes)."""

    def __init__(self, snapshot: Snapshot) -> None:
        self.snapshot = snapshot

    def before(self, command: Command) -> None:
        pass

    def after(self, command: Command, answer: object, error: BaseException | None) -> None:
        self.snapshot.changed()


class Control:
    """The plant as the control API sees it."""

    def __init__(self, plant: Plant, runner: Runner, bus: EventBus) -> None:
        self.plant = plant
        self.runner = runner
        self.bus = bus
        # no request reads a file; a console advance through the API ends at a stop
        # (SIGTERM) with the run around it
        # a long console command (advance, power break) is a runner mode, as step is
        self.console = Console(
            plant, files=False, interrupted=lambda: runner.stopping, modes=self._console_mode
        )
        self.mode_ended: Future[Json] | None = None  # the end of the last mode started
        self._console_started: Future[Json] | None = None  # a mode a console line started
        self._exchanges: OrderedDict[int, _Started] = OrderedDict()
        self._next_exchange = 1
        # the reads that change nothing, as the simulation's thread last made them
        self.snapshot = Snapshot()
        self._ids: dict[str, Device] = {}  # devices(), as last made
        self._ids_key: tuple[tuple[int, object], ...] | None = None
        self._held: tuple[Device, ...] = ()
        # every command through the plant's door (API, attached console, scenario) makes
        # it stale before its answer goes out: a later read sees the command's effect
        plant.door.watch(_Stale(self.snapshot))
        # the series' rings, sampled on the runner's tick beside the observers (trends.py)
        self.trends = Trends(plant)

    # --- the plant and its devices -----------------------------------------------

    def devices(self) -> dict[str, Device]:
        """Each device by its id (a copy: the caller may keep or change it)."""
        return dict(self._by_id())

    def _by_id(self) -> dict[str, Device]:
        """The ids, made again only when a device or an address changed (a module
        removed or inserted, a TES's slave number): a command's lookup is one pass
        over the devices, not n x n."""
        devices = self.plant.devices
        key = tuple((id(d), d.address) for d in devices)
        if key != self._ids_key:
            self._ids = {device_id(d, devices): d for d in devices}
            self._ids_key = key
            self._held = tuple(devices)  # kept alive: no other object takes their id()
        return self._ids

    def device(self, ident: str) -> Device:
        found = self._by_id()
        device = found.get(ident)
        if device is None:
            raise NotFound(f"no device {ident!r} (allowed: {', '.join(found) or 'none'})")
        return device

    def plant_json(self) -> Json:
        plc = self.plant.plc
        return {
            "title": self.plant.title,
            "name": self.plant.name,
            "clock": self.clock_json(),
            # RUN, STOP or FAULT, and why (the task watchdog: docs/pl7.md)
            "plc": None if plc is None else {"mode": plc.mode, "fault": plc.fault},
            "devices": [
                {
                    "id": ident,
                    "kind": d.kind,
                    "family": d.family.value,
                    "address": str(d.address),
                    "state": d.status().state,
                }
                for ident, d in self.devices().items()
            ],
        }

    def status(self, ident: str) -> Json:
        return {"id": ident, **status_json(self.device(ident).status())}

    def leds(self, ident: str) -> dict[str, str]:
        return dict(self.device(ident).status().leds)

    # --- inputs and faults ---------------------------------------------------------

    def inputs(self, ident: str) -> list[Json]:
        return [
            {"name": i.name, "description": i.description, "signal": i.driver is not None}
            for i in self.device(ident).inputs().values()
        ]

    def set_input(
        self, ident: str, name: str, value: bool | float | str | None, signal: object
    ) -> Json:
        device = self.device(ident)
        if (value is None) == (signal is None):
            raise ConfigError('give either "value" or "signal" (a signal table), not both')
        point = self._input(device, name)
        where = f"input {ident} {name}"
        if signal is not None:
            refuse_files(signal, f"{where}.signal")
            assert isinstance(signal, Mapping)
            point.drive(signal, where=where, base_dir=None)
            return {"device": ident, "input": point.name, "signal": dict(signal)}
        assert value is not None
        point.set(value)
        return {"device": ident, "input": point.name, "value": value}

    @staticmethod
    def _input(device: Device, name: str) -> Input:
        try:
            return device.input(name)
        except ConfigError as exc:
            raise NotFound(str(exc)) from None

    def faults(self, ident: str) -> list[Json]:
        """The faults that apply to the device, each active or not, with its parameters."""
        return [fault_json(f) for f in self.device(ident).faults().values()]

    def outputs(self, ident: str) -> list[Json]:
        """Every output the device drives, in its units (volts, milliamps), raw word beside."""
        return [output_json(o.read(), o.description) for o in self.device(ident).outputs().values()]

    def set_fault(self, ident: str, name: str, active: bool, params: Mapping[str, float]) -> Json:
        device = self.device(ident)
        try:
            fault = device.fault(name)
        except FaultNotApplicable:
            raise  # a line fault none of its ports carries: 400, naming where it applies
        except ConfigError as exc:
            raise NotFound(str(exc)) from None
        numbers = {k: int(v) if float(v).is_integer() else v for k, v in params.items()}
        fault.set(active, **numbers)
        return {"device": ident, "fault": fault.name, "active": active, "params": numbers}

    # --- objects ---------------------------------------------------------------------

    def objects(self, ident: str) -> list[str]:
        return [entry.text for entry in self.device(ident).objects().names()]

    def read_object(self, ident: str, name: str, peek: bool) -> Json:
        objects = self.device(ident).objects()
        value = objects.peek(name) if peek else objects.read(name)
        return {"device": ident, "object": name, "value": value, "hex": format_hex(value)}

    def write_object(self, ident: str, name: str, value: int) -> Json:
        objects = self.device(ident).objects()
        objects.write(name, value)
        now = objects.peek(name)
        return {"device": ident, "object": name, "value": now, "hex": format_hex(now)}

    def power_cycle(self, ident: str, seconds: float | None = None) -> Json:
        """24 V off and on again; with ``seconds``, on again that many simulated seconds
        later (an outage that lasts: fieldtwin.plant.outage)."""
        device = self.device(ident)
        if device.family is not Family.TES:
            raise ConfigError(
                f"{device.kind} {device.address}: power-cycle is for a TES;"
                " a module loses its supply with the PLC's power break"
            )
        try:
            back = outage.power_cycle(self.plant.clock, device, seconds, ident)
        except outage.OutageBusy as exc:
            raise Conflict(str(exc)) from None
        if back is None:
            return {"device": ident, "power": "cycled"}
        return {"device": ident, "power": "off", "back_at_s": back / S}

    # --- the PLC: Text Blocks, power, slots ---------------------------------------------

    @property
    def plc(self) -> Plc:
        if self.plant.plc is None:
            raise ConfigError("this plant has no PLC (add a [plc] table or [[module]] tables)")
        return self.plant.plc

    def start_exchange(
        self,
        m: int,
        c: int,
        send: list[int],
        text: str | None,
        length: int | None,
        recv: int,
        txt: int,
    ) -> Json:
        data = None
        if text is not None:
            try:
                data = text.encode("latin-1")
            except UnicodeEncodeError:
                raise ConfigError("text: allowed ISO 8859-1 characters only") from None
        plc = self.plc
        try:
            block = plc.start_exchange(
                m,
                c,
                None if data is not None else send,
                send_bytes=data,
                length=length,
                recv_bytes=recv,
                txt=txt,
            )
        except ConfigError as exc:
            raise Conflict(str(exc)) from None
        ident = self._next_exchange
        self._next_exchange += 1
        self._exchanges[ident] = _Started(ident, block, m, c)
        while len(self._exchanges) > MAX_EXCHANGES:
            self._exchanges.popitem(last=False)
        return self.exchange(ident)

    def exchange(self, ident: int) -> Json:
        started = self._exchanges.get(ident)
        if started is None:
            raise NotFound(f"no exchange {ident} (the last {MAX_EXCHANGES} are kept)")
        block, result = started.block, started.block.result
        out: Json = {
            "id": ident,
            "txt": block.index,
            "m": format_hex(started.m),
            "c": format_hex(started.c, 2),
            "state": block.state.value,
            "done": block.done,
            "result": None,
        }
        if block.done and result is not None:
            out["result"] = {
                result.report_name: result.v,
                "V": result.v,
                "S": result.s,
                "E": int(result.e),
                "error": result.error_text,
                "words": result.words,
                "data": result.data.hex(),
                "ended_at_s": result.ended_at,
            }
        return out

    def power_break(self, seconds: float) -> Json:
        """The PLC's supply cut now, back in ``seconds``: a runner mode (the clock section)."""
        self.runner.end_mode()  # a break in progress ends (power back) before this one
        power_back = self.plc.cut_power(seconds)
        until = self.plant.clock.now + to_us(seconds)
        return self._start("power-break", until, "power back", power_back)

    def _slot(self, module: str) -> tuple[int, int]:
        """A module's rack and slot; NotFound (404) for a slot without a module."""
        modules = self.plc.modules
        allowed = ", ".join(str(m.rack * 10 + m.slot) for m in modules)
        try:
            rack, slot = module_address(module)
        except ConfigError as exc:
            raise NotFound(f"{exc}; no such module (allowed: {allowed})") from None
        if not any((m.rack, m.slot) == (rack, slot) for m in modules):
            raise NotFound(f"no module in rack {rack} slot {slot} (allowed: {allowed})")
        return rack, slot

    def remove(self, module: str) -> Json:
        rack, slot = self._slot(module)
        self.plc.remove(rack, slot)
        return {"module": module, "present": False}

    def insert(self, module: str) -> Json:
        rack, slot = self._slot(module)
        self.plc.reinsert(rack, slot)
        return {"module": module, "present": True}

    # --- the clock -----------------------------------------------------------------------
    # step, run-until and power-break are runner modes (docs/control.md, "The clock"): the
    # command starts one and answers at once; the mode's end is a clock event that
    # publishes a clock event and settles ``mode_ended`` (what a waiting request awaits).

    def clock_json(self) -> Json:
        """The clock as GET /clock shows it: its state and the speed reached (measured
        on the wall, so never part of a command's answer, which a replay gives again)."""
        reached = self.runner.speed_reached
        return {
            **self.clock_state(),
            "speed_reached": None if reached is None else float(f"{reached:.4g}"),
            "speed_kept": not self.runner.lagging,
        }

    def clock_state(self) -> Json:
        speed, mode = self.runner.speed, self.runner.mode
        return {
            "t_s": self.plant.clock.now / S,
            "t_us": self.plant.clock.now,
            "paused": self.runner.paused,
            "speed": "max" if speed is None else speed,
            "mode": None if mode is None else mode.name,
            "until_s": None if mode is None else mode.until / S,
        }

    def _clock_event(self, what: str, extra: Json | None = None) -> Json:
        state = {**self.clock_state(), **(extra or {})}
        self.bus.publish(self.plant.clock.now, "clock", "clock", {"what": what, **state})
        return state

    def _start(
        self, name: str, until: int, what: str, then: Callable[[], None] | None = None
    ) -> Json:
        """Start the runner mode ``name`` until ``until``; ``then`` runs at its end."""
        ended: Future[Json] = Future()
        ended.set_running_or_notify_cancel()  # a waiter that leaves cannot cancel it
        power: Json = {"power": "off"} if then is not None else {}

        def end(now: int, cut: bool) -> None:
            if then is not None:
                then()
            back = {"power": "back"} if then is not None else {}
            self.snapshot.changed()  # before a waiting request has its answer
            ended.set_result(self._clock_event(what, {**back, "cut": cut}))

        self.runner.start_mode(name, until, end)
        self.mode_ended = ended
        return self._clock_event(name, power)

    def pause(self) -> Json:
        self.runner.pause()
        return self._clock_event("paused")

    def resume(self) -> Json:
        self.runner.resume()
        return self._clock_event("resumed")

    def step(self, ms: float) -> Json:
        return self._start("step", self.plant.clock.now + round(ms * MS), "stepped")

    def run_until(self, t_s: float) -> Json:
        try:
            return self._start("run-until", round(t_s * S), "ran")
        except ConfigError as exc:  # a time already past
            raise Conflict(str(exc)) from None

    def set_speed(self, speed: float | None) -> Json:
        self.runner.set_speed(speed)
        self.plant.speed = speed
        return self._clock_event("speed")

    # --- the console -------------------------------------------------------------------

    def _console_mode(self, name: str, duration_us: int) -> list[str]:
        """A console ``advance`` or ``power break``: the runner mode, started now."""
        if duration_us < 0:
            raise ConfigError(f"{name}: cannot run simulated time backwards")
        until = self.plant.clock.now + duration_us
        if name == "power break":
            self.power_break(duration_us / S)
            started = f"power off until t = {until / S:.3f} s"
        else:
            self._start("advance", until, "advanced")
            started = f"advancing to t = {until / S:.3f} s"
        self._console_started = self.mode_ended
        return [f"{started} (a mode: pause, speed and reads are served meanwhile)"]

    def take_console_mode(self) -> Future[Json] | None:
        """The end of the mode the last console line started (once), or None."""
        started, self._console_started = self._console_started, None
        return started

    def console_mode_answer(self, ended: Json) -> Json:
        """A console line's answer once the mode it started has ended, as the
        stand-alone console answers the same line."""
        now = f"t = {self.plant.clock.now / S:.3f} s"
        if ended.get("cut"):
            first = f"interrupted  {now}"
        elif ended.get("power") == "back":
            first = f"power back  {now}"
        else:
            first = now
        return {"lines": [first, *self.console.trace.pending()], "error": None}

    def console_line(self, line: str, text: str | None = None) -> Json:
        """One console command line on the running plant: its lines, or its error.

        The console reads no file here: ``prog load -`` takes the program's ``text``,
        a command that names a file is refused (docs/control.md, "The console")."""
        try:
            return {"lines": self.console.execute(line, text), "error": None}
        except FieldtwinError as exc:
            return {"lines": [], "error": str(exc)}


__all__ = [
    "MAX_EXCHANGES",
    "Conflict",
    "Control",
    "NotFound",
    "device_id",
    "refuse_files",
    "status_json",
]
