"""``fieldtwin replay FILE`` and ``fieldtwin diff A B`` (docs/record.md).

A replay rebuilds the plant a recording embeds (or ``--plant other.toml``) on a
fresh simulated clock, binds its ports as the recording did but on virtual
endpoints (nothing real is opened), and feeds the recorded inputs - wire
bytes, connections, control-API calls, console lines - each at its simulated
instant, between the same two clock events, as fast as the machine allows.
Every output it produces is compared with the recorded ones: same record, same
simulated instant, in the same order.  Exit 0 when identical, 1 with the first
difference shown in context, 2 for a file that is not a recording.
"""

from __future__ import annotations

import argparse
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldtwin.clock import MS
from fieldtwin.console import Console
from fieldtwin.control.resources import Control
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.plant import Plant, PlantFile, build_plant, embedded_plant, read_plant
from fieldtwin.runtime.binder import bind
from fieldtwin.runtime.record import (
    INPUTS,
    OUTPUTS,
    CharsFeed,
    Header,
    Record,
    Sampler,
    iter_records,
    plain_json,
    read_header,
)
from fieldtwin.runtime.replay import Comparer, ReplayClock, ReplayRunner
from fieldtwin.runtime.wall import SystemWall
from fieldtwin.transports.virtual import Wiring

# The control API's commands that are recorded (docs/record.md): every Control method a
# route calls, except the pure readers (plant, status, LEDs, lists) and console_line,
# whose console line the console records itself.
CONTROL_COMMANDS = (
    "set_input",
    "set_fault",
    "read_object",
    "write_object",
    "power_cycle",
    "start_exchange",
    "exchange",
    "power_break",
    "remove",
    "insert",
    "pause",
    "resume",
    "step",
    "run_until",
    "set_speed",
)


@dataclass(frozen=True, slots=True)
class Outcome:
    """What a replay found."""

    identical: bool
    difference: str | None
    expected: int  # output records of the recording
    produced: int  # output records of the replay
    inputs: int
    sim_us: int  # simulated time replayed
    wall_s: float  # how long it took

    @property
    def speed(self) -> float:
        """Simulated seconds per wall second."""
        return self.sim_us / 1e6 / self.wall_s if self.wall_s > 0 else float("inf")


def replay(path: str | Path, plant_path: str | Path | None = None) -> Outcome:
    """Replay the recording ``path`` (against ``plant_path`` when given).

    Two passes over the file: the inputs (and the end) first, then the recorded
    outputs, compared one by one as the replay produces them."""
    header = read_header(path)
    inputs = list(iter_records(path, INPUTS | {"end"}))
    end = inputs.pop() if inputs and inputs[-1][0] == "end" else None
    comparer = Comparer(iter_records(path, OUTPUTS))
    with tempfile.TemporaryDirectory(prefix="fieldtwin-replay-") as tmp:
        if plant_path is None:
            plant_file = embedded_plant(header, str(path), Path(tmp))
        else:
            plant_file = read_plant(plant_path)
        wall_clock = SystemWall()
        started = wall_clock.monotonic()
        sim_us = _play(header, plant_file, inputs, end, comparer, wall_clock)
        wall = wall_clock.monotonic() - started
    difference = comparer.finish()
    return Outcome(
        difference is None,
        None if difference is None else difference.text,
        comparer.expected,
        comparer.produced,
        len(inputs),
        sim_us,
        wall,
    )


def _play(
    header: Header,
    plant_file: PlantFile,
    inputs: Sequence[Record],
    end: Record | None,
    out: Comparer,
    wall: SystemWall,
) -> int:
    clock = ReplayClock()
    runner = ReplayRunner(clock, header.speed, inputs, wall)
    runner.out = out
    with Wiring():
        plant = build_plant(plant_file, runner=runner, speed=header.speed)
        try:
            chars = CharsFeed(plant.events, out.append)
            sampler = Sampler(clock, plant.devices, out.append, header.sample_ms * MS)
            control = Control(plant, runner, plant.events)
            runner.dispatch = _Dispatcher(plant, runner, control, header.console)
            runner.play()
            if end is not None:
                runner.finish(end[1], end[2])
            chars.close()
            sampler.close()
        finally:
            plant.close()
    return clock.now


class _Dispatcher:
    """Binds, control calls and console lines of a recording, on the replayed plant."""

    def __init__(
        self, plant: Plant, runner: ReplayRunner, control: Control, console: str = "inline"
    ) -> None:
        self.plant = plant
        self.runner = runner
        self.control = control
        # console lines run as they ran when recorded (the header's console): the
        # control API's console (modes) or a Python session's (inline)
        self.console = control.console if console == "modes" else Console(plant, files=False)

    def __call__(self, record: Record) -> None:
        kind = record[0]
        if kind == "bind":
            groups = tuple(str(g) for g in record[3])
            self.plant.bindings.append(
                bind(self.plant.devices, self.runner, groups=groups, events=self.plant.events)
            )
        elif kind == "call":
            name, args = str(record[3]), list(record[4])
            if name not in CONTROL_COMMANDS:
                raise ConfigError(f"recording: {name!r} is not a recorded control command")
            self._command(name, lambda: getattr(self.control, name)(*args))
        elif kind == "line":
            line = str(record[3])
            self._command("console", lambda: self.console.execute(line))

    def _command(self, label: str, run: Any) -> None:
        try:
            answer = plain_json(run())
        except FieldtwinError as exc:
            answer = {"error": str(exc)}
        self.runner.take_ret()
        self.runner.out.append(["result", self.runner.clock.now, label, answer])


def diff(a: str | Path, b: str | Path) -> str | None:
    """The first difference between two recordings (inputs first, then outputs), or None;
    both are read as streams, never whole."""
    read_header(a)
    read_header(b)
    names = (str(a), str(b))
    parts: list[str] = []
    for label, kinds in (("inputs", INPUTS), ("outputs", OUTPUTS)):
        comparer = Comparer(iter_records(a, kinds), names=names)
        for record in iter_records(b, kinds):
            comparer.append(record)
        found = comparer.finish()
        if found is not None:
            text = found.text.replace("output", "input", 1) if label == "inputs" else found.text
            parts.append(f"{label}: {text}")
    return "\n".join(parts) if parts else None


# ------------------------------------------------------------------------- the commands


def add_parsers(sub: Any) -> None:
    rep = sub.add_parser("replay", help="replay a recording and check every output is the same")
    rep.add_argument("recording", help="a file written by fieldtwin run --record")
    rep.add_argument("--plant", help="replay the same inputs against this plant file instead")
    dif = sub.add_parser("diff", help="compare two recordings")
    dif.add_argument("a", help="a recording")
    dif.add_argument("b", help="another recording")


def run_replay(args: argparse.Namespace) -> int:
    outcome = replay(args.recording, args.plant)
    summary = (
        f"{outcome.inputs} inputs, {outcome.expected} outputs recorded,"
        f" {outcome.produced} replayed; {outcome.sim_us / 1e6:.3f} simulated s in"
        f" {outcome.wall_s:.2f} s (x{outcome.speed:.0f})"
    )
    if outcome.identical:
        print(f"identical: {summary}", flush=True)
        return 0
    print(f"different: {summary}", flush=True)
    print(outcome.difference, flush=True)
    return 1


def run_diff(args: argparse.Namespace) -> int:
    text = diff(args.a, args.b)
    if text is None:
        print("identical: same inputs, same outputs", flush=True)
        return 0
    print(text, flush=True)
    return 1


__all__ = ["CONTROL_COMMANDS", "Outcome", "diff", "replay"]
