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
import inspect
import tempfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from fieldtwin.clock import MS
from fieldtwin.console import Console
from fieldtwin.control.resources import Control
from fieldtwin.control.sim import serve
from fieldtwin.errors import FieldtwinError
from fieldtwin.facade.host import OsHost
from fieldtwin.plant import PlantFile, build_plant, embedded_plant, read_plant
from fieldtwin.runtime.binder import ALL
from fieldtwin.runtime.door import Command
from fieldtwin.runtime.recfile import RecordingError
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
from fieldtwin.runtime.recstream import extent
from fieldtwin.runtime.recstream import records as numbered_records
from fieldtwin.runtime.replay import Comparer, Feed, ReplayClock, ReplayRunner
from fieldtwin.runtime.wall import SystemWall
from fieldtwin.session import CONTROL_COMMANDS, Session
from fieldtwin.transports.virtual import Wiring


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

    Two streams over the file, side by side: the inputs (and the end), delivered as
    the replay reaches them, and the recorded outputs, compared one by one as the
    replay produces them; neither is ever held whole.  A recording is untrusted input
    (fieldtwin.runtime.recfile): anything out of its bounds refuses the replay with
    a ConfigError naming the file and the line."""
    where = str(path)
    header = read_header(path)
    feed = Feed(numbered_records(path, INPUTS | {"end"}), where)
    expected = iter_records(path, OUTPUTS)
    comparer = Comparer(expected, on_error=feed.fail)
    try:
        with tempfile.TemporaryDirectory(prefix="fieldtwin-replay-") as tmp:
            if plant_path is None:
                plant_file = confined_plant(header, where, Path(tmp))
            else:
                plant_file = read_plant(plant_path)
            wall_clock = SystemWall()
            started = wall_clock.monotonic()
            runner = _play(header, plant_file, feed, comparer, wall_clock, extent(path))
            wall = wall_clock.monotonic() - started
        difference = None if feed.failure is not None else comparer.finish()
    finally:
        feed.close()
        expected.close()
    if feed.failure is not None:
        raise feed.failure
    text = None if difference is None else difference.text
    if text is not None and runner.overrun is not None:
        line, asked = runner.overrun
        text += (
            f"\n(the replay stopped at the recording's end, t = {runner.limit_us / 1e6:.6f} s:"
            f" the command of line {line} asked to run to t = {asked / 1e6:g} s)"
        )
    return Outcome(
        difference is None,
        text,
        comparer.expected,
        comparer.produced,
        feed.count,
        runner.clock.now,
        wall,
    )


def confined_plant(header: Header, where: str, directory: Path) -> PlantFile:
    """The plant a recording embeds, its files written into ``directory``, confined
    there: a value that would name a file outside it (an absolute path, a ``..``) and
    that the recording does not embed is refused, so a replay reads and writes only
    its own temporary folder and fieldtwin's own programs."""
    plant_file = embedded_plant(header, where, directory)
    for key, value in _strings(plant_file.data, ""):
        if "://" in value:  # an endpoint (tcp://, serial:///dev/...): a replay opens none
            continue
        name = PurePosixPath(value)
        if name.is_absolute() or ".." in name.parts:
            raise RecordingError(
                f"{where}: line 1: the recorded plant's {key} = {value[:80]!r} is a path"
                " outside the replay's folder (absolute, or with '..') that the recording"
                " does not embed: refused (a replay reads and writes only its own folder"
                " and the files the recording embeds; to replay against a plant file of"
                " yours, give it with --plant)"
            )
    return plant_file


def _strings(value: object, key: str) -> Iterator[tuple[str, str]]:
    if isinstance(value, str):
        yield key, value
    elif isinstance(value, Mapping):
        for name, item in value.items():
            yield from _strings(item, f"{key}.{name}" if key else str(name))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _strings(item, f"{key}[{index}]")


def _play(
    header: Header,
    plant_file: PlantFile,
    feed: Feed,
    out: Comparer,
    wall: SystemWall,
    limit_us: int,
) -> ReplayRunner:
    clock = ReplayClock()
    runner = ReplayRunner(clock, header.speed, feed, wall, limit_us)
    runner.out = out
    # nothing real is opened: the binder and the PLC's host open virtual twins
    backends = Wiring().backends
    plant = build_plant(plant_file, runner=runner, speed=header.speed, host=OsHost(backends))
    with Session(plant, runner, backends) as session:
        session.own_ports()  # what the recording binds closes with the plant
        chars = CharsFeed(plant.events, out.append)
        sampler = Sampler(clock, plant.devices, out.append, header.sample_ms * MS)
        control = Control(plant, runner, plant.events)
        serve(plant.door, control)  # the recorded calls run as the live API ran them
        runner.dispatch = _Dispatcher(session, runner, control, header.console)
        runner.play()
        if feed.end is not None:
            runner.finish(feed.end[1], feed.end[2])
        chars.close()
        sampler.close()
    return runner


class _Dispatcher:
    """Binds, control calls and console lines of a recording, on the replayed plant.

    What a recording asks that the plant cannot do (an unknown command, arguments
    of the wrong kind, a port group that does not exist) refuses the replay, naming
    the line (``feed.refuse``): nothing is raised through the plant's own code."""

    def __init__(
        self, session: Session, runner: ReplayRunner, control: Control, console: str = "inline"
    ) -> None:
        self.session = session
        plant = self.plant = session.plant
        self.runner = runner
        self.control = control
        # console lines run as they ran when recorded (the header's console): the
        # control API's console (modes) or a Python session's (inline)
        self.console = (
            control.console
            if console == "modes"
            else Console(plant, files=False, interrupted=lambda: runner.stopping)
        )

    def __call__(self, record: Record) -> None:
        kind, feed = record[0], self.runner.feed
        line = feed.line
        if kind == "bind":
            groups = tuple(str(g) for g in record[3])
            unknown = sorted(set(groups) - set(ALL))
            if unknown:
                feed.refuse(line, f"bind: unknown port group(s) {unknown} (allowed: {ALL})")
                return
            try:
                self.session.bind(groups)
            except FieldtwinError as exc:
                feed.refuse(line, f"bind: {exc}")
                return
        elif kind == "call":
            name, args = str(record[3]), list(record[4])
            if name not in CONTROL_COMMANDS:
                feed.refuse(line, f"{name[:40]!r} is not a recorded control command")
                return
            method = getattr(self.control, name)
            try:
                inspect.signature(method).bind(*args)
            except TypeError as exc:
                feed.refuse(line, f"control {name}: {exc} ({len(args)} arguments recorded)")
                return
            command = Command.call(name, *args)  # re-submitted through the plant's door
            self._command(line, f"control {name}", name, lambda: self.plant.door.dispatch(command))
        elif kind == "line":
            text = str(record[3])  # the console runs it through the plant's door
            self._command(line, "console line", "console", lambda: self.console.execute(text))

    def _command(self, line: int, what: str, label: str, run: Callable[[], object]) -> None:
        feed = self.runner.feed
        self.runner.command_lines.append(line)
        try:
            answer = plain_json(run())
        except FieldtwinError as exc:
            answer = {"error": str(exc)}
        except RecursionError:
            feed.refuse(line, f"{what}: nested too deeply")
            return
        except (TypeError, ValueError, ArithmeticError, LookupError, AttributeError) as exc:
            # arguments of a kind the API's schema would have refused
            feed.refuse(line, f"{what}: refused ({type(exc).__name__}: {str(exc)[:200]})")
            return
        finally:
            self.runner.command_lines.pop()
        if feed.failure is not None:  # refused while it ran (its own run, a later line)
            return
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
    rep = sub.add_parser(
        "replay",
        help="replay a recording and check every output is the same",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
        "  fieldtwin run plant.toml --record session.ftrec --duration 60 --no-live\n"
        "  fieldtwin replay session.ftrec                 # exit 0: identical, 1: different\n"
        "  fieldtwin replay session.ftrec --plant fixed.toml   # the same inputs, another plant",
    )
    rep.add_argument("recording", help="a file written by fieldtwin run --record")
    rep.add_argument("--plant", help="replay the same inputs against this plant file instead")
    dif = sub.add_parser(
        "diff",
        help="compare two recordings",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
        "  fieldtwin diff before.ftrec after.ftrec        # the first difference, or nothing",
    )
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


__all__ = ["CONTROL_COMMANDS", "Outcome", "confined_plant", "diff", "replay"]
