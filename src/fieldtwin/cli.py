"""The `fieldtwin` command: run, console, trace, tesis."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from typing import TYPE_CHECKING, TextIO, cast

from fieldtwin import __version__
from fieldtwin.errors import ConfigError, FieldtwinError

if TYPE_CHECKING:
    from fieldtwin.plant import Plant
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
        "  fieldtwin run --speed max --duration 60 --no-live --status-every 10\n"
        "  fieldtwin run --scenario examples/scenarios/fault_drill.toml --speed max --no-live",
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
    run.add_argument(
        "--scenario",
        metavar="FILE",
        help="run this scenario (TOML, docs/scenarios.md) from t = 0 and stop after it:"
        " exit 0 when every expectation held, 1 naming the first that did not",
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
    """``fieldtwin run``: the options, to the session that runs them (fieldtwin.session)."""
    from fieldtwin.plant import FROM_PLANT
    from fieldtwin.session import ControlOptions, RunOptions, run

    control = ControlOptions(
        args.control_host, args.control_port, args.control_token, args.allow_origin
    )
    options = RunOptions(
        plant=args.plant,
        speed=FROM_PLANT if args.speed is SUPPRESS_SPEED else args.speed,
        duration_s=args.duration,
        live=not args.no_live,
        status_every_s=args.status_every,
        trace=args.trace,
        pcap=args.pcap,
        record=args.record,
        control=None if args.no_control else control,
        scenario=args.scenario,
    )
    return run(options)


def _console(args: argparse.Namespace) -> int:
    from fieldtwin.plant import FROM_PLANT
    from fieldtwin.session import Session

    if args.attach is not None:
        return _attached(args)
    speed = FROM_PLANT if args.speed is SUPPRESS_SPEED else args.speed
    with Session.for_console(args.plant, speed) as session:
        return _console_lines(args, session.plant)


def _console_lines(args: argparse.Namespace, plant: Plant) -> int:
    from fieldtwin.console import Console, run_script
    from fieldtwin.control.scenarios import fallback_handlers

    console = Console(plant)
    console.call = fallback_handlers(plant)["call"]  # a scenario's steps (docs/scenarios.md)
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


def stop_on_signals(runner: Runner) -> None:
    """SIGTERM/SIGINT end the run (kept here for callers of ``fieldtwin.cli``; the
    handler lives with the session)."""
    from fieldtwin.session import stop_on_signals as install

    install(runner)
