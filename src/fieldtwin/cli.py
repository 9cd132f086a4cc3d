"""The `fieldtwin` command: run, console, trace, tesis."""

from __future__ import annotations

import argparse
import gc
import math
import os
import signal
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import replace
from typing import TYPE_CHECKING, TextIO, cast

from fieldtwin import __version__
from fieldtwin.clock import S, SimClock
from fieldtwin.errors import ConfigError, FieldtwinError

if TYPE_CHECKING:
    from rich.live import Live

    from fieldtwin.control.launch import Launched
    from fieldtwin.plant import Plant
    from fieldtwin.runtime.binder import Binding
    from fieldtwin.runtime.events import EventBus
    from fieldtwin.runtime.runner import Runner

SUPPRESS_SPEED: object = object()  # --speed not given: the plant's [run] speed decides
# Issue 20 item 9: the exit status when the reader of the output went away (`| head -1`):
# 128 + SIGPIPE, what a shell shows for `yes | head -1` (docs/decisions.md,
# "Connection limit and broken pipes")
PIPE_CLOSED = 141


def _speed(text: str) -> float | None:
    from fieldtwin.runtime.pace import MAX_SPEED, MIN_SPEED

    if text.lower() == "max":
        return None
    try:
        value = float(text.lower().removeprefix("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} not allowed (allowed: a speed factor such as 1, 10 or x10, or max)"
        ) from None
    if not MIN_SPEED <= value <= MAX_SPEED:
        raise argparse.ArgumentTypeError(
            f"{text!r}: the speed factor must be from {MIN_SPEED:g} to {MAX_SPEED:g} (or max)"
        )
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0 <= value < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: simulated seconds (a number >= 0)")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fieldtwin", description="Executable twins of TSX Series 7 modules and Leroy TES."
    )
    parser.add_argument("--version", action="version", version=f"fieldtwin {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser(
        "run",
        help="bring a plant to life in real time",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
        "  fieldtwin run                                  # the embedded default plant, x1\n"
        "  fieldtwin run examples/tes.toml --speed 10\n"
        "  fieldtwin run --speed max --duration 60 --no-live --status-every 10",
    )
    run.add_argument("plant", nargs="?", help="plant file (TOML); default: the embedded plant")
    run.add_argument(
        "--speed",
        type=_speed,
        default=SUPPRESS_SPEED,
        help="x1, x10 (0.001 to 100000), or max (default: the plant's [run] speed, else x1)",
    )
    run.add_argument("--duration", type=_seconds, help="stop after this many simulated seconds")
    run.add_argument("--no-live", action="store_true", help="no live view, plain status lines")
    run.add_argument(
        "--status-every", type=_seconds, default=0.0, help="with --no-live: status every N sim. s"
    )
    run.add_argument("--trace", metavar="FILE", help="write the traffic as JSON lines")
    run.add_argument(
        "--pcap", metavar="FILE", help="write the Modbus TCP and RTU line traffic as a pcap"
    )
    run.add_argument(
        "--record",
        metavar="FILE",
        help="record the session for `fieldtwin replay` (docs/record.md)",
    )
    _control_options(run)
    con = sub.add_parser(
        "console",
        help="the programming terminal",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
        '  fieldtwin console --speed max -c "advance 12" -c "read IW5,0 IW5,3"\n'
        "  fieldtwin console examples/aem811.toml --script session.txt\n"
        '  fieldtwin console --attach $FIELDTWIN_URL -c "faults 5"   # a running plant',
    )
    con.add_argument("plant", nargs="?", help="plant file (TOML); default: the embedded plant")
    con.add_argument("--script", "-f", help="run commands from this file ('-' = stdin)")
    con.add_argument(
        "--command", "-c", dest="commands", action="append", help="run this command (repeatable)"
    )
    con.add_argument(
        "--speed",
        type=_speed,
        default=SUPPRESS_SPEED,
        help="pacing while real endpoints exist: x1, x10, or max (default: [run] speed, else x1)",
    )
    con.add_argument(
        "--attach",
        metavar="URL",
        help="run the commands on the plant `fieldtwin run` serves at URL (docs/control.md)",
    )
    con.add_argument("--token", help="with --attach: the control token the run printed")
    sub.add_parser("tesis", help="the TES parameter workbench (fieldtwin tesis --help)")
    from fieldtwin.tracecli import add_parser as add_trace_parser

    add_trace_parser(sub)
    from fieldtwin.replay import add_parsers as add_replay_parsers

    add_replay_parsers(sub)
    return parser


def _port(text: str) -> int:
    if not text.isdigit() or not 0 <= int(text) <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: a TCP port 0..65535 (0 = any free port)")
    return int(text)


def _control_options(run: argparse.ArgumentParser) -> None:
    run.add_argument(
        "--control-port",
        type=_port,
        default=None,
        help="the control API's port (default 8520, or any free one if busy; 0 = any free)",
    )
    run.add_argument("--no-control", action="store_true", help="no control API")
    run.add_argument(
        "--control-host",
        default=None,
        help="the control API's address (default 127.0.0.1 without a token; when given,"
        " every request needs the token)",
    )
    run.add_argument(
        "--control-token", help="the token every request must give (default: generated)"
    )
    run.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="a web origin (http://host:port) whose pages may call the control API besides"
        " the plant's own; repeatable (default: none)",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """The `fieldtwin` command; exit status PIPE_CLOSED, quietly, when its output was lost."""
    try:
        try:
            return _main(argv)
        finally:
            if sys.stdout is not None:  # None: started with its stdout closed (>&-)
                sys.stdout.flush()  # here, not at the interpreter's exit: a broken pipe is seen
    except BrokenPipeError:
        _pipe_gone(sys.stdout)
        _pipe_gone(sys.stderr, only_if_broken=True)
        return PIPE_CLOSED


def _pipe_gone(stream: TextIO | None, only_if_broken: bool = False) -> None:
    """Point ``stream``'s descriptor at /dev/null: what is still buffered, and whatever
    is printed later, goes nowhere instead of raising (the recipe of Python's signal
    module documentation, "Note on SIGPIPE")."""
    if stream is None:  # the process started without it (>&-)
        return
    if only_if_broken:
        try:
            stream.flush()
            return
        except BrokenPipeError:
            pass
        except (OSError, ValueError):
            return
    with suppress(OSError, ValueError, AttributeError):  # not a real descriptor (a test's)
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, stream.fileno())
        finally:
            os.close(devnull)
    with suppress(OSError, ValueError):
        stream.flush()


class _Reader:
    """The standard output or error of `fieldtwin run`: when its reader goes away
    (``| head -1``, a log pager that quits), printing stops and the plant keeps
    serving (issue 20 item 9); said once on the other stream."""

    def __init__(self, stream: TextIO, name: str) -> None:
        self._stream = stream
        self._name = name
        self.gone = False
        self.other: _Reader | None = None

    def write(self, text: str) -> int:
        if not self.gone:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self._lose()
        return len(text)

    def flush(self) -> None:
        if not self.gone:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self._lose()

    def _lose(self) -> None:
        self.gone = True
        _pipe_gone(self._stream)
        if self.other is not None:
            self.other.write(
                f"fieldtwin: the reader of the {self._name} went away; the plant keeps"
                " running without printing there\n"
            )
            self.other.flush()

    def __getattr__(self, name: str) -> object:  # isatty, fileno, encoding ...
        return getattr(self._stream, name)


@contextmanager
def _readers() -> Iterator[tuple[_Reader, _Reader]]:
    """sys.stdout and sys.stderr as ``_Reader`` while `run` runs."""
    saved = sys.stdout, sys.stderr
    with open(os.devnull, "w") as nowhere:  # for a stream the process started without (>&-)
        out = _Reader(saved[0] or nowhere, "output")
        err = _Reader(saved[1] or nowhere, "error output")
        out.other, err.other = err, out
        sys.stdout, sys.stderr = cast(TextIO, out), cast(TextIO, err)
        try:
            yield out, err
        finally:
            sys.stdout, sys.stderr = saved


def _main(argv: Sequence[str] | None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["tesis"]:  # the workbench parses its own options (--store, --model...)
        from fieldtwin.tes.tesis import main as tesis_main

        try:
            return int(tesis_main(words[1:]))
        except FieldtwinError as exc:
            print(f"fieldtwin tesis: {exc}", file=sys.stderr)
            return 2
    args = _parser().parse_args(words)
    try:
        if args.command == "run":
            with _readers() as (out, _):
                status = _run(args)
            return PIPE_CLOSED if out.gone else status
        if args.command == "trace":
            from fieldtwin.tracecli import run_trace

            return run_trace(args)
        if args.command in ("replay", "diff"):
            from fieldtwin.replay import run_diff, run_replay

            return run_replay(args) if args.command == "replay" else run_diff(args)
        return _console(args)
    except FieldtwinError as exc:
        print(f"fieldtwin: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C while loading or opening endpoints: no traceback
        print("fieldtwin: interrupted", file=sys.stderr)
        return 130


def _run(args: argparse.Namespace) -> int:
    from fieldtwin.live import footer_urls, plain_status, render
    from fieldtwin.plant import build_plant, plant_speed, read_plant
    from fieldtwin.runtime.binder import ALL, bind
    from fieldtwin.runtime.exposure import warnings_for
    from fieldtwin.runtime.runner import Runner

    plant_file = read_plant(args.plant)
    own_speed = plant_speed(plant_file)  # checked even when --speed overrides it
    speed = own_speed if args.speed is SUPPRESS_SPEED else args.speed
    clock = SimClock()
    runner = Runner(clock, speed)
    stop_on_signals(runner)  # from here on a stop is never lost (issue 20)
    plant = build_plant(plant_file, runner=runner, speed=speed)
    plant.events.start()  # the observers' work on a thread of theirs (DESIGN rule 13)
    control: Launched | None = None
    try:
        recorders = _recorders(args, plant.events)  # before any port opens: no frame is missed
        _start_recording(args, plant, runner, recorders)
        # the control API starts before any port opens: its imports and its server's start
        # take a second, and a master connecting at the `running` line must be served
        control = _start_control(args, plant, runner, plant.events)
        if control is not None and plant.recorder is not None:
            from fieldtwin.replay import CONTROL_COMMANDS

            plant.recorder.instrument(control.server.control, CONTROL_COMMANDS)
        plant.note_bound(ALL)
        binding = bind(plant.devices, runner, events=plant.events)  # every port, once built
    except BaseException:
        if control is not None:
            control.close()
        plant.events.close()
        plant.close()
        raise
    plant.bindings.append(binding)
    plant.bindings.append(recorders)
    endpoints = binding.lines
    for line in endpoints:
        print(line, flush=True)
    for warning in warnings_for(endpoints):  # issue 10 item 7
        print(warning, file=sys.stderr, flush=True)
    for note in plant.notes:  # e.g. an analog level beyond the converter's span (TES §4.2.4)
        print(f"fieldtwin: note: {note}", file=sys.stderr, flush=True)
    print(
        f"running {plant.title} at {'max speed' if speed is None else f'x{speed:g}'}",
        flush=True,
    )
    if control is not None:  # after the `running` line; the API is up already
        # one bus for every window onto the plant: the API's stream sees the traffic too
        # a moved port (8520 busy) is said before the URL lines it corrects
        for warning in control.warnings:
            print(warning, file=sys.stderr, flush=True)
        for line in control.lines:
            print(line, flush=True)
    # the plant lives as long as the process: the cyclic collector need not walk its
    # objects again and again (1000 TES: half the time of an edge; docs/decisions.md)
    gc.collect()
    gc.freeze()
    live = sys.stdout.isatty() and not args.no_live
    end = None if args.duration is None else clock.now + round(args.duration * S)
    next_status = [clock.now]
    urls = [] if control is None else footer_urls(control.lines)  # the live view's footer

    def tick(now: int) -> None:
        if control is not None:
            control.observer.sample(now)
        if end is not None and now >= end:
            runner.stop()
        if live_view is not None:
            live_view.update(render(plant, endpoints, runner, urls))
        elif args.status_every > 0 and now >= next_status[0]:
            next_status[0] = now + round(args.status_every * S)
            print("\n".join(plain_status(plant)), flush=True)

    live_view: Live | None = None
    try:
        if live:
            from rich.live import Live

            view = render(plant, endpoints, runner, urls)
            with Live(view, refresh_per_second=5) as live_view:
                runner.run_forever(tick, tick_us=_tick(speed))
        else:
            runner.run_forever(tick, tick_us=_tick(speed))
    finally:
        if _HAS_TIMER:
            signal.setitimer(signal.ITIMER_REAL, 0)  # the run ended: no forced stop
        for number in (signal.SIGTERM, signal.SIGINT):  # closing: a signal cuts it short
            signal.signal(number, _interrupt)
        final = [] if live else plain_status(plant)  # the plant as it stopped (issue 10 item 21)
        if control is not None:
            control.close()
        plant.events.close()  # what the observers still hold reaches the files first
        plant.close()
    if final:
        print("\n".join(final), flush=True)
    print(f"stopped at t = {clock.now / S:.3f} s", flush=True)
    return 0


STOP_GRACE_S = 1.5  # after SIGTERM/SIGINT, the most wall time the run has to end by itself


_HAS_TIMER = hasattr(signal, "setitimer") and hasattr(signal, "SIGALRM")  # not on Windows


def _interrupt(*_: object) -> None:
    raise KeyboardInterrupt


def stop_on_signals(runner: Runner) -> None:
    """SIGTERM and SIGINT end the run within STOP_GRACE_S (issue 20, docs/decisions.md
    "Bounded catch-up and runner modes"): the first asks ``runner.stop()`` (a latch, not
    lost if it comes before the run starts) and arms a timer; if the run has not ended
    when it rings (an instant that never ends), or at a second signal, KeyboardInterrupt
    is raised where the program stands, and the plant is closed on the way out."""

    def stop(*_: object) -> None:
        if runner.stopping:
            _interrupt()
        runner.stop()
        if _HAS_TIMER:  # POSIX; elsewhere a second Ctrl-C cuts the run short
            signal.setitimer(signal.ITIMER_REAL, STOP_GRACE_S)

    if _HAS_TIMER:
        signal.signal(signal.SIGALRM, _interrupt)
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)


def _recorders(args: argparse.Namespace, events: EventBus) -> Binding:
    """The --trace and --pcap writers, closed (flushed) with the plant."""
    from fieldtwin.runtime.binder import Binding
    from fieldtwin.runtime.pcap import PcapWriter
    from fieldtwin.runtime.trace import TraceWriter

    def report(text: str) -> None:
        print(f"fieldtwin: {text}", file=sys.stderr, flush=True)

    recorders = Binding()
    try:
        if args.trace:
            recorders.add([], TraceWriter(events, args.trace, report=report).close)
        if args.pcap:
            recorders.add([], PcapWriter(events, args.pcap, report=report, rtu_lines=True).close)
    except BaseException:
        recorders.close()
        raise
    return recorders


def _start_recording(
    args: argparse.Namespace, plant: Plant, runner: Runner, recorders: Binding
) -> None:
    """--record FILE: the plant's inputs and outputs from t = 0 (docs/record.md)."""
    if not args.record:
        return
    from fieldtwin.plant import recording_header
    from fieldtwin.runtime.record import Recorder

    assert plant.source is not None
    # console lines reach `fieldtwin run` through the control API only, whose console
    # runs an advance or power break as a runner mode: replayed the same way
    header = replace(recording_header(plant.source, runner.speed), console="modes")
    recorder = Recorder(args.record, header, plant.clock, plant.devices, plant.events, runner)
    plant.recorder = recorder

    def close() -> None:
        recorder.close()
        if recorder.waited is not None:  # docs/record.md: a recording is never cut short
            print(f"fieldtwin: {recorder.waited}", file=sys.stderr, flush=True)

    recorders.add([], close)


def _start_control(
    args: argparse.Namespace, plant: Plant, runner: Runner, bus: EventBus
) -> Launched | None:
    """The control API (docs/control.md), unless --no-control; its lines are printed later."""
    if args.no_control:
        return None
    from fieldtwin.control.launch import launch

    launched = launch(
        plant,
        runner,
        bus,
        host=args.control_host,
        port=args.control_port,
        token=args.control_token,
        allow_origins=args.allow_origin,
    )
    return launched


def _tick(speed: float | None) -> int:
    return 200_000 if speed is None else max(50_000, round(200_000 * speed))


def _console(args: argparse.Namespace) -> int:
    from fieldtwin.console import Console, run_script
    from fieldtwin.plant import FROM_PLANT, load_plant, plant_speed, read_plant

    if args.attach is not None:
        return _attached(args)
    speed = FROM_PLANT if args.speed is SUPPRESS_SPEED else args.speed
    plant_speed(read_plant(args.plant))  # an invalid [run] speed is reported even with --speed
    plant = load_plant(args.plant, speed=speed)
    for note in plant.notes:
        print(f"fieldtwin: note: {note}", file=sys.stderr, flush=True)
    console = Console(plant)
    if args.commands:
        return run_script(console, args.commands, sys.stdout, sys.stderr, "-c")
    if args.script:
        if args.script == "-":
            return run_script(console, sys.stdin, sys.stdout, sys.stderr, "<stdin>")
        lines = _script_lines(args.script)
        if lines is None:
            return 2
        return run_script(console, lines, sys.stdout, sys.stderr, args.script)
    if not sys.stdin.isatty():
        return run_script(console, sys.stdin, sys.stdout, sys.stderr, "<stdin>")
    from fieldtwin.terminal import interactive

    return interactive(console, plant)


MAX_SCRIPT_BYTES = 16 * 1024 * 1024  # a console script file (docs/console.md)


def _script_lines(path: str) -> list[str] | None:
    """A console script's lines, read with bounds (a regular UTF-8 file); None, said on
    stderr, when it cannot be read."""
    from fieldtwin.textfile import read_text

    try:
        return read_text(path, MAX_SCRIPT_BYTES, "console script").splitlines()
    except ConfigError as exc:
        print(f"fieldtwin: {exc}", file=sys.stderr)
        return None


def _attached(args: argparse.Namespace) -> int:
    """``console --attach URL``: the same commands, run on a running plant."""
    from fieldtwin.control.attach import explain, interactive, run_remote
    from fieldtwin.control.client import Client, ControlError

    if args.plant is not None:
        print(
            "fieldtwin: console --attach takes no plant file (the running plant is used)",
            file=sys.stderr,
        )
        return 2
    with Client(args.attach, token=args.token) as client:
        if args.commands:
            return run_remote(client, args.commands, sys.stdout, sys.stderr, "-c")
        if args.script and args.script != "-":
            lines = _script_lines(args.script)
            if lines is None:
                return 2
            return run_remote(client, lines, sys.stdout, sys.stderr, args.script)
        if args.script == "-" or not sys.stdin.isatty():
            return run_remote(client, sys.stdin, sys.stdout, sys.stderr, "<stdin>")
        try:
            client.plant()  # unreachable or refused: a clear error, status 2
        except ControlError as exc:
            print(f"fieldtwin: {explain(exc, client)}", file=sys.stderr)
            return 2
        return interactive(client)


if __name__ == "__main__":
    sys.exit(main())
