"""The Session: the one place a plant is put to work, and taken down again.

``fieldtwin run``, ``fieldtwin console``, ``fieldtwin replay`` (and, through
``fieldtwin run``, the testing package's running plant) each compose their
plant here.  A session holds one built plant (fieldtwin.plant: a value that
opens nothing) and the runner that paces it, and opens, in order:

1. the windows that write files (``--trace``, ``--pcap``, ``--record``): they
   subscribe before anything moves, so no frame is missed;
2. the observers' thread of the event bus (DESIGN rule 13);
3. the control API (its server starts before any port opens: a master
   connecting at the ``running`` line must be served);
4. the plant's ports, through the runtime's binder, group by group.

Each step pushes how it is undone; ``close()`` undoes them in reverse (ports,
control API, the bus - what the observers still hold reaches the files -, the
writers), every one of them even when one fails, on an error during start-up,
at the end of the run and after SIGTERM / SIGINT (``stop_on_signals``).
"""

from __future__ import annotations

import gc
import signal
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

from fieldtwin.clock import S, SimClock
from fieldtwin.control.sim import COMMANDS
from fieldtwin.plant import FROM_PLANT, Plant, build_plant, load_plant, plant_speed, read_plant
from fieldtwin.plant.reading import recording_header
from fieldtwin.runtime.binder import ALL
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.backends import REAL, Backends

if TYPE_CHECKING:
    from rich.live import Live

    from fieldtwin.control.launch import Launched
    from fieldtwin.runtime.record import Recorder
    from fieldtwin.scenario import Scenario, ScenarioRun

# The control API's commands that are recorded (docs/record.md): the door's CALL commands.
CONTROL_COMMANDS = COMMANDS
STOP_GRACE_S = 1.5  # after SIGTERM/SIGINT, the most wall time the run has to end by itself
_HAS_TIMER = hasattr(signal, "setitimer") and hasattr(signal, "SIGALRM")  # not on Windows


def _say(text: str, err: bool = False) -> None:
    print(text, file=sys.stderr if err else sys.stdout, flush=True)


@dataclass(frozen=True, slots=True)
class ControlOptions:
    """The control API's options (docs/control.md)."""

    host: str | None = None
    port: int | None = None
    token: str | None = None
    allow_origins: Sequence[str] = ()


@dataclass(frozen=True, slots=True)
class RunOptions:
    """What ``fieldtwin run`` is asked (docs/cli: ``fieldtwin run --help``)."""

    plant: str | None = None
    speed: float | str | None = FROM_PLANT  # a factor, None (max), or the plant's own
    duration_s: float | None = None
    live: bool = True  # the live view, when the output is a terminal
    status_every_s: float = 0.0
    trace: str | None = None
    pcap: str | None = None
    record: str | None = None
    control: ControlOptions | None = field(default_factory=ControlOptions)  # None: no API
    scenario: str | None = None  # a scenario file: run it from t = 0, end after it


class Session:
    """One plant, its runner, the windows onto it; everything closed in reverse."""

    def __init__(
        self, plant: Plant, runner: Runner | None = None, backends: Backends = REAL
    ) -> None:
        self.plant = plant
        self.backends = backends  # what opens the ports (a replay's are virtual)
        self.runner = runner
        self.lines: list[str] = []  # the `listening: ...` lines, in the order bound
        self.control: Launched | None = None
        self._undo: list[Callable[[], None]] = []
        self._ports = False  # the plant's ports are closed by the session

    # --- composing ------------------------------------------------------------

    @classmethod
    def for_console(cls, path: str | Path | None, speed: float | str | None) -> Session:
        """The console's plant: its module ports (SCM channels) open, the TES closed."""
        plant_speed(read_plant(path))  # an invalid [run] speed is reported even with --speed
        session = cls(load_plant(path, speed=speed))
        session.own_ports()
        for note in session.plant.notes:
            _say(f"fieldtwin: note: {note}", err=True)
        return session

    def push(self, undo: Callable[[], None]) -> None:
        """How the step just taken is undone (done in reverse by ``close``)."""
        self._undo.append(undo)

    def own_ports(self) -> None:
        """The plant's ports (opened already, or from now on) close with the session,
        at the point of this step."""
        if not self._ports:
            self._ports = True
            self.push(self.plant.close)

    def bind(self, groups: tuple[str, ...] = ALL) -> list[str]:
        """Open the plant's ports of ``groups``; their `listening:` lines."""
        plant = self.plant
        self.own_ports()
        binding = plant.ports.bind(plant.devices, self.runner, groups, plant.events, self.backends)
        self.lines.extend(binding.lines)
        return binding.lines

    def write_files(self, trace: str | None = None, pcap: str | None = None) -> None:
        """The --trace and --pcap writers, flushed and closed with the session: in the
        observers' process when it runs (the file checked here first), else here."""
        from fieldtwin.runtime.pcap import PcapWriter
        from fieldtwin.runtime.trace import TraceWriter

        events = self.plant.events

        def report(text: str) -> None:
            _say(f"fieldtwin: {text}", err=True)

        def closing(close: Callable[[], None]) -> Callable[[], None]:
            def both() -> None:
                events.close()  # what the observers hold reaches the file first
                close()

            return both

        link = events.link
        for option, path in (("trace", trace), ("pcap", pcap)):
            if not path:
                continue
            if link is not None:
                writable(option, path)
                link.write(option, path)
            elif option == "trace":
                self.push(closing(TraceWriter(events, path, report=report).close))
            else:
                writer = PcapWriter(events, path, report=report, rtu_lines=True)
                self.push(closing(writer.close))

    def record(self, path: str) -> Recorder:
        """--record FILE: the plant's inputs and outputs from t = 0 (docs/record.md)."""
        from fieldtwin.runtime.record import Recorder

        plant, runner = self.plant, self.runner
        assert plant.source is not None and runner is not None
        # console lines reach `fieldtwin run` through the control API only, whose console
        # runs an advance or power break as a runner mode: replayed the same way
        header = replace(recording_header(plant.source, runner.speed), console="modes")
        recorder = Recorder(
            path, header, plant.clock, plant.devices, plant.events, runner, door=plant.door
        )
        plant.ports.set_recorder(recorder)

        def close() -> None:
            recorder.close()
            if recorder.waited is not None:  # docs/record.md: a recording is never cut short
                _say(f"fieldtwin: {recorder.waited}", err=True)

        self.push(close)
        return recorder

    def start_events(self, process: bool = False) -> None:
        """The observers' work on a thread of theirs, or in a process of their own
        (``process``; DESIGN rule 13, fieldtwin.runtime.obslink)."""
        from fieldtwin.runtime.obslink import ObserversProcess

        self.plant.events.start(ObserversProcess.start if process else None)
        self.push(self.plant.events.close)  # what the observers hold reaches the files

    def start_control(self, options: ControlOptions) -> Launched:
        """The control API (docs/control.md); its lines are printed by ``announce``."""
        from fieldtwin.control.launch import launch

        assert self.runner is not None
        launched = launch(
            self.plant,
            self.runner,
            self.plant.events,
            host=options.host,
            port=options.port,
            token=options.token,
            allow_origins=options.allow_origins,
        )
        self.push(launched.close)
        self.control = launched  # the recorder sees its commands at the plant's door
        return launched

    def start_scenario(self, scenario: Scenario) -> ScenarioRun:
        """``--scenario``: its steps and expectations from now; the run stops at its end."""
        from fieldtwin.control.scenarios import fallback_handlers
        from fieldtwin.scenario import ScenarioRun

        runner = self.runner
        assert runner is not None
        handlers = fallback_handlers(self.plant, runner)
        run = ScenarioRun(
            self.plant,
            scenario,
            call=handlers["call"],
            line=handlers["line"],
            on_end=lambda result: runner.stop(),
        )
        self.push(run.cancel)
        return run.start()

    def announce(self) -> None:
        """The listening lines, warnings and notes, the `running` line, the API's lines."""
        from fieldtwin.runtime.exposure import warnings_for

        plant, speed = self.plant, self.plant.speed
        for line in self.lines:
            _say(line)
        for warning in warnings_for(self.lines):  # issue 10 item 7
            _say(warning, err=True)
        for note in plant.notes:  # e.g. an analog level beyond the converter's span
            _say(f"fieldtwin: note: {note}", err=True)
        _say(f"running {plant.title} at {'max speed' if speed is None else f'x{speed:g}'}")
        if self.control is not None:  # after the `running` line; the API is up already
            for warning in self.control.warnings:  # a moved port (8520 busy) first
                _say(warning, err=True)
            for line in self.control.lines:
                _say(line)

    # --- closing ---------------------------------------------------------------

    def close(self) -> None:
        """Undo every step, last first; each one even when another fails (the first
        failure is raised once all are done)."""
        failure: BaseException | None = None
        while self._undo:
            undo = self._undo.pop()
            try:
                undo()
            except BaseException as exc:  # a second Ctrl-C too: the rest still closes
                failure = failure or exc
        if failure is not None:
            raise failure

    def __enter__(self) -> Session:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


# ------------------------------------------------------------------ fieldtwin run


def open_run(options: RunOptions) -> Session:
    """The plant of ``options`` built and every window and port opened, in order."""
    plant_file = read_plant(options.plant)
    own_speed = plant_speed(plant_file)  # checked even when --speed overrides it
    speed = own_speed if options.speed == FROM_PLANT else options.speed
    assert not isinstance(speed, str)
    runner = Runner(SimClock(), speed)
    stop_on_signals(runner)  # from here on a stop is never lost (issue 20)
    session = Session(build_plant(plant_file, runner=runner, speed=speed), runner)
    try:
        session.start_events(process=True)  # the trace and pcap are written there
        session.write_files(options.trace, options.pcap)  # before any port opens
        if options.record:
            session.record(options.record)
        if options.control is not None:  # before the ports: a master may connect at once
            session.start_control(options.control)
        session.bind(ALL)
    except BaseException:
        session.close()
        raise
    return session


def run(options: RunOptions) -> int:
    """``fieldtwin run``: open, announce, run until stopped, close; exit status 0 (with
    ``--scenario``: 0 when every expectation held, else 1 naming the first that did not)."""
    from fieldtwin.scenario import read_scenario

    scenario = read_scenario(options.scenario) if options.scenario else None  # before any port
    session = open_run(options)
    try:
        if scenario is not None:
            scenario_run = session.start_scenario(scenario)
        session.announce()
        # the plant lives as long as the process: the cyclic collector need not walk its
        # objects again and again (1000 TES: half the time of an edge; docs/decisions.md)
        gc.collect()
        gc.freeze()
        live = options.live and sys.stdout.isatty()
        _serve(session, options, live)
    finally:
        if _HAS_TIMER:
            signal.setitimer(signal.ITIMER_REAL, 0)  # the run ended: no forced stop
        for number in (signal.SIGTERM, signal.SIGINT):  # closing: a signal cuts it short
            signal.signal(number, _interrupt)
        final = [] if options.live and sys.stdout.isatty() else _status(session.plant)
        session.close()
    if final:
        _say("\n".join(final))
    _say(f"stopped at t = {session.plant.clock.now / S:.3f} s")
    if scenario is None:
        return 0
    result = scenario_run.result
    _say("\n".join(result.lines()))
    if not result.done:
        _say(f"fieldtwin: scenario {scenario.name}: stopped before its end", err=True)
    elif not result.passed:
        _say(f"fieldtwin: {result.summary()}", err=True)
    return 0 if result.passed else 1


def writable(option: str, path: str) -> None:
    """``--trace``/``--pcap`` ``path`` can be written (created empty now), or ConfigError."""
    from fieldtwin.errors import ConfigError

    try:
        with open(path, "wb"):
            pass
    except OSError as exc:
        raise ConfigError(f"--{option} {path}: cannot write it ({exc.strerror})") from None


def _status(plant: Plant) -> list[str]:
    from fieldtwin.live import plain_status

    return plain_status(plant)  # the plant as it stopped (issue 10 item 21)


def _serve(session: Session, options: RunOptions, live: bool) -> None:
    """Run until stopped: the live view, or status lines every N simulated seconds."""
    from fieldtwin.live import footer_urls, plain_status, render

    plant, runner, control = session.plant, session.runner, session.control
    assert runner is not None
    clock = plant.clock
    end = None if options.duration_s is None else clock.now + round(options.duration_s * S)
    next_status = [clock.now]
    urls = [] if control is None else footer_urls(control.lines)  # the live view's footer
    live_view: Live | None = None

    def tick(now: int) -> None:
        if control is not None:
            control.observer.sample(now)
            if control.trends is not None:
                control.trends.sample(now)
        if end is not None and now >= end:
            runner.stop()
        if live_view is not None:
            live_view.update(render(plant, session.lines, runner, urls))
        elif options.status_every_s > 0 and now >= next_status[0]:
            next_status[0] = now + round(options.status_every_s * S)
            _say("\n".join(plain_status(plant)))

    tick_us = 200_000 if plant.speed is None else max(50_000, round(200_000 * plant.speed))
    if live:
        from rich.live import Live

        with Live(render(plant, session.lines, runner, urls), refresh_per_second=5) as view:
            live_view = view
            runner.run_forever(tick, tick_us=tick_us)
    else:
        runner.run_forever(tick, tick_us=tick_us)


def _interrupt(*_: object) -> None:
    raise KeyboardInterrupt


def stop_on_signals(runner: Runner) -> None:
    """SIGTERM and SIGINT end the run within STOP_GRACE_S (issue 20, docs/decisions.md
    "Bounded catch-up and runner modes"): the first asks ``runner.stop()`` (a latch, not
    lost if it comes before the run starts) and arms a timer; if the run has not ended
    when it rings (an instant that never ends), or at a second signal, KeyboardInterrupt
    is raised where the program stands, and the session is closed on the way out."""

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


__all__ = [
    "CONTROL_COMMANDS",
    "STOP_GRACE_S",
    "ControlOptions",
    "RunOptions",
    "Session",
    "open_run",
    "run",
    "stop_on_signals",
]
