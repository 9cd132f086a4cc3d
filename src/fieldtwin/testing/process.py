"""A real ``fieldtwin run`` in a subprocess, on free ports, always torn down.

:func:`start_plant` (and the ``running_plant`` fixture) starts ``fieldtwin run
PLANT --no-live --control-port 0`` with every TCP endpoint of the plant file on a
free port, waits (bounded) for its ``listening:`` and ``control:`` lines, and
yields a :class:`RunningPlant`: the control client, the endpoints as they were
opened, and the run's output.  Leaving the ``with`` block -- by a failure, an
exception or a KeyboardInterrupt -- stops the process (SIGTERM, then SIGKILL).

Free ports without a race: each distinct ``tcp://`` / ``rtu+tcp://`` endpoint of
the file gets port 0 (the system picks a free port when it listens), spelled
``0``, ``00``, ``000`` ... so that endpoints that were distinct stay distinct.  The
rewritten file is written next to the original (a hidden sibling, removed at the
end), so that programs, CSV files and stores named relative to it are found.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import re
import subprocess
import sys
import threading
import time
import tomllib
import uuid
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import IO, Any

from fieldtwin.client import Client, ControlError
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.testing.targets import time_text

START_S = 60.0  # the plant prints its control line within this (wall) bound
STOP_S = 15.0  # SIGTERM, then SIGKILL after this
POLL_S = 0.02  # run_until's poll period (wall)
DEFAULT_SCENARIO_WALL_S = 120.0  # a scenario on a running plant: the most it is awaited (wall)
SCENARIO_POLL_S = 0.1
MAX_LINES = 5000  # output lines kept per stream (the last ones)
_TCP = re.compile(r"^((?:rtu\+)?tcp://)(\[[^\]]*\]|[^:/]+):(\d+)$")
_LISTENING = re.compile(
    r"^listening: (?P<what>.*?) (?P<where>(?:rtu\+)?tcp://\S+|pty \S+|serial://\S+)"
)
_SLAVES = re.compile(r" slaves ([\d,]+)")

_live: set[RunningPlant] = set()  # stopped at exit too: nothing outlives the test run


class PlantStartError(FieldtwinError):
    """``fieldtwin run`` ended or said nothing within the bound: its output is in the message."""


@dataclass(frozen=True, slots=True)
class Endpoint:
    """One ``listening:`` line: what listens, where, for which slaves."""

    what: str  # "modbus-tcp", "modbus-rtu-over-tcp", "TSX SCM 2111 slot 7 channel 0"...
    url: str  # "tcp://127.0.0.1:40411", "rtu+tcp://...", "/dev/pts/4" (a pty's path)
    slaves: tuple[int, ...]  # the TES slave numbers answering there (Modbus endpoints)
    declared: str | None  # the plant file's endpoint, for a Modbus endpoint
    line: str

    @property
    def host(self) -> str:
        return self._tcp()[0]

    @property
    def port(self) -> int:
        return self._tcp()[1]

    def _tcp(self) -> tuple[str, int]:
        match = _TCP.match(self.url)
        if match is None:
            raise ConfigError(f"{self.what} listens on {self.url}, not on a TCP port")
        return match.group(2).strip("[]"), int(match.group(3))


def _endpoints_of(data: dict[str, object]) -> list[str]:
    """The endpoint strings of a plant file, in file order: TES, then module channels."""
    found: list[str] = []
    for table in data.get("tes", []) or []:  # type: ignore[attr-defined]
        if isinstance(table, dict) and isinstance(table.get("endpoint"), str):
            found.append(table["endpoint"])
    for table in data.get("module", []) or []:  # type: ignore[attr-defined]
        channels = table.get("channels", []) if isinstance(table, dict) else []
        for channel in channels if isinstance(channels, list) else []:
            if isinstance(channel, dict) and isinstance(channel.get("endpoint"), str):
                found.append(channel["endpoint"])
    return found


def free_ports_text(text: str, name: str) -> tuple[str, dict[str, str]]:
    """The plant text with every TCP endpoint on port 0 (distinct ones kept distinct),
    and the mapping declared -> rewritten."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{name}: not valid TOML: {exc}") from None
    mapping: dict[str, str] = {}
    for url in _endpoints_of(data):
        match = _TCP.match(url.strip())
        if match is None or url in mapping:
            continue
        mapping[url] = f"{match.group(1)}{match.group(2)}:{'0' * (len(mapping) + 1)}"
    for old, new in mapping.items():
        for quote in ('"', "'"):
            text = text.replace(f"{quote}{old}{quote}", f"{quote}{new}{quote}")
    rewritten = _endpoints_of(tomllib.loads(text))
    if rewritten != [mapping.get(u, u) for u in _endpoints_of(data)]:
        raise ConfigError(
            f"{name}: cannot move its endpoints to free ports (write each endpoint as a plain"
            ' string, e.g. endpoint = "tcp://127.0.0.1:5020")'
        )
    return text, mapping


_LOCK = threading.Lock()  # the readers append while a report copies


def _read(stream: IO[str], sink: deque[str], ready: Callable[[str], None]) -> None:
    with contextlib.suppress(ValueError, OSError):
        for line in stream:
            text = line.rstrip("\n")
            with _LOCK:
                sink.append(text)
            ready(text)


# The child's first lines (``python -c``): on Linux it asks for SIGTERM when the test
# process dies without tearing it down (PR_SET_PDEATHSIG, set in the child's own main
# thread: no preexec_fn after a fork of a threaded process), then runs `fieldtwin`.
_BOOT = """\
import os, runpy, signal, sys
if sys.platform.startswith("linux"):
    try:
        import ctypes
        ctypes.CDLL(None).prctl(1, signal.SIGTERM)
    except (OSError, AttributeError):
        pass
    if str(os.getppid()) != os.environ.get("FIELDTWIN_TEST_PARENT"):
        sys.exit(3)  # the test process is already gone
sys.argv = ["fieldtwin", *sys.argv[1:]]
runpy.run_module("fieldtwin", run_name="__main__", alter_sys=True)
"""


_COPY = re.compile(r"^\.(?P<stem>.+)\.fieldtwin-(?P<pid>\d+)-[0-9a-f]{8}\.toml$")


def _remove_stale_copies(home: Path, stem: str) -> None:
    """The copies a killed test process left beside the plant file (its pid is gone)."""
    try:
        names = [p for p in home.iterdir() if p.name.startswith(f".{stem}.fieldtwin-")]
    except OSError:
        return
    for path in names:
        match = _COPY.match(path.name)
        if match is None or match.group("stem") != stem:
            continue
        try:
            os.kill(int(match.group("pid")), 0)
        except ProcessLookupError:
            with contextlib.suppress(OSError):
                path.unlink()
        except (PermissionError, OverflowError):
            continue


class RunningPlant:
    """A ``fieldtwin run`` subprocess and the ways in: ``client``, ``url``, ``endpoints``."""

    def __init__(self, plant: Path | None, *, speed: float | str | None, args: Sequence[str]):
        self.declared = plant  # the user's plant file (None: the embedded default plant)
        self.speed = speed
        self.args = list(args)
        self.url = ""
        self.client: Client | None = None  # set once started
        self.endpoints: list[Endpoint] = []
        self.stdout: deque[str] = deque(maxlen=MAX_LINES)
        self.stderr: deque[str] = deque(maxlen=MAX_LINES)
        self.mapping: dict[str, str] = {}
        self.command: list[str] = []
        self._copy: Path | None = None
        self._proc: subprocess.Popen[str] | None = None
        self._started = threading.Event()
        self._threads: list[threading.Thread] = []

    # --- life ---------------------------------------------------------------------

    def _plant_file(self) -> Path:
        if self.declared is None:
            text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text()
            name, home = "<default plant>", None
        else:
            try:
                text = self.declared.read_text("utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise ConfigError(f"{self.declared}: cannot read the plant file ({exc})") from None
            name, home = str(self.declared), self.declared.resolve().parent
        text, self.mapping = free_ports_text(text, name)
        if home is None:
            import tempfile

            home = Path(tempfile.mkdtemp(prefix="fieldtwin-plant-"))
        stem = self.declared.stem if self.declared is not None else "default"
        _remove_stale_copies(home, stem)
        copy = home / f".{stem}.fieldtwin-{os.getpid()}-{uuid.uuid4().hex[:8]}.toml"
        try:
            copy.write_text(text, "utf-8")
        except OSError as exc:
            raise ConfigError(
                f"{name}: cannot write its free-port copy {copy} ({exc.strerror})"
            ) from None
        self._copy = copy
        return copy

    def start(self, start_s: float = START_S) -> RunningPlant:
        plant = self._plant_file()
        self.command = ["fieldtwin", "run", str(plant), "--no-live"]
        self.command += ["--control-port", "0"]
        if self.speed is not None:
            self.command += ["--speed", str(self.speed)]
        self.command += self.args
        env = dict(os.environ, COLUMNS="200", PYTHONUNBUFFERED="1")
        env["FIELDTWIN_TEST_PARENT"] = str(os.getpid())
        self._proc = subprocess.Popen(
            [sys.executable, "-c", _BOOT, *self.command[1:]],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=plant.parent,
            env=env,
        )
        _live.add(self)

        def on_line(text: str) -> None:
            if text.startswith("attach: "):
                self._started.set()

        assert self._proc.stdout is not None and self._proc.stderr is not None
        for stream, sink, ready in (
            (self._proc.stdout, self.stdout, on_line),
            (self._proc.stderr, self.stderr, lambda _t: None),
        ):
            thread = threading.Thread(target=_read, args=(stream, sink, ready), daemon=True)
            thread.start()
            self._threads.append(thread)
        deadline = time.monotonic() + start_s
        while not self._started.wait(0.05):
            if self._proc.poll() is not None:
                self._join_readers()
                raise PlantStartError(
                    f"fieldtwin run {self._plant_name()} ended with status"
                    f" {self._proc.returncode} before it was ready\n{self.output()}"
                )
            if time.monotonic() > deadline:
                raise PlantStartError(
                    f"fieldtwin run {self._plant_name()} not ready within {start_s:g} s"
                    f"\n{self.output()}"
                )
        self._parse_lines()
        self.client = Client(self.url)
        return self

    def _join_readers(self) -> None:
        for thread in self._threads:
            thread.join(timeout=5)

    def _parse_lines(self) -> None:
        modbus_declared = list(dict.fromkeys(self._tes_endpoints()))
        modbus = 0
        with _LOCK:
            lines = list(self.stdout)
        for line in lines:
            if line.startswith("control: "):
                self.url = line.split()[1]
            match = _LISTENING.match(line)
            if match is None:
                continue
            where = match.group("where")
            url = where[4:] if where.startswith("pty ") else where
            slaves = _SLAVES.search(line)
            numbers = tuple(int(s) for s in slaves.group(1).split(",")) if slaves else ()
            declared = None
            if match.group("what").startswith("modbus-") and modbus < len(modbus_declared):
                declared = modbus_declared[modbus]
                modbus += 1
            self.endpoints.append(Endpoint(match.group("what"), url, numbers, declared, line))

    def _tes_endpoints(self) -> list[str]:
        """The plant file's TES endpoints (as written), in file order."""
        if self.declared is None:
            text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text()
        else:
            text = self.declared.read_text("utf-8")
        tables = tomllib.loads(text).get("tes", [])
        return [str(t.get("endpoint")) for t in tables if isinstance(t, dict)]

    def alive(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc is not None else None

    @property
    def returncode(self) -> int | None:
        return self._proc.returncode if self._proc is not None else None

    def stop(self) -> None:
        """SIGTERM, wait (bounded), SIGKILL; close the client; remove the copy."""
        _live.discard(self)
        try:
            if self.client is not None:
                self.client.close()
            proc = self._proc
            if proc is not None and proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(timeout=STOP_S)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(timeout=STOP_S)
            self._join_readers()
            if proc is not None:
                for stream in (proc.stdout, proc.stderr):
                    if stream is not None:
                        stream.close()
        finally:
            if self._copy is not None:
                with contextlib.suppress(OSError):
                    self._copy.unlink()
                if self.declared is None:
                    with contextlib.suppress(OSError):
                        self._copy.parent.rmdir()

    # --- what it says -----------------------------------------------------------

    def _plant_name(self) -> str:
        return str(self.declared) if self.declared is not None else "(the default plant)"

    def output(self) -> str:
        """The run's command, stdout and stderr (what a failing test's report shows)."""
        parts = [f"$ {' '.join(self.command)}"]
        if self._copy is not None:
            parts.append(
                f"# {self._copy.name}: {self._plant_name()} with its TCP endpoints on free ports"
            )
        with _LOCK:
            parts += ["--- stdout ---", *self.stdout, "--- stderr ---", *self.stderr]
        if self._proc is not None and self._proc.returncode is not None:
            parts.append(f"--- exit status {self._proc.returncode} ---")
        return "\n".join(parts)

    # --- the ways in --------------------------------------------------------------

    @property
    def api(self) -> Client:
        if self.client is None:
            raise ConfigError("the plant is not running (start() it first)")
        return self.client

    def modbus(self, slave: int, declared: str | None = None) -> Endpoint:
        """The Modbus endpoint where TES ``slave`` answers (``declared``: the plant
        file's endpoint, when that slave number answers on several)."""
        found = [
            e
            for e in self.endpoints
            if slave in e.slaves and (declared is None or e.declared == declared)
        ]
        if len(found) == 1:
            return found[0]
        have = "; ".join(e.line for e in self.endpoints if e.slaves) or "no Modbus endpoint"
        if not found:
            raise ConfigError(f"no Modbus endpoint answers slave {slave} (have: {have})")
        raise ConfigError(
            f"slave {slave} answers on {len(found)} endpoints: give declared= (have: {have})"
        )

    def channel(self, module: str, channel: int) -> Endpoint:
        """A module channel's endpoint (an SCM channel's pty or TCP listener)."""
        for e in self.endpoints:
            if e.what.endswith(f" slot {module} channel {channel}"):
                return e
        lines = "; ".join(e.line for e in self.endpoints) or "none"
        raise ConfigError(f"no endpoint for slot {module} channel {channel} (have: {lines})")

    def target(self) -> RunningTarget:
        return RunningTarget(self)

    # --- scenarios (docs/scenarios.md) ------------------------------------------

    def scenario(self, path: Path, wall_s: float = DEFAULT_SCENARIO_WALL_S) -> dict[str, Any]:
        """Start the scenario file ``path`` (``POST /scenarios``) and await its end, at most
        ``wall_s`` wall seconds; its result (``done`` false if it did not end by then)."""
        try:
            text = Path(path).read_text("utf-8")
        except OSError as exc:
            raise ConfigError(f"{path}: cannot read the scenario file ({exc.strerror})") from None
        api = self.api
        started = api.request("POST", "/scenarios", {"text": text, "name": Path(path).name})
        deadline = time.monotonic() + wall_s
        while True:
            result: dict[str, Any] = api.request("GET", f"/scenarios/{started['id']}")
            if result["done"] or time.monotonic() > deadline:
                return result
            time.sleep(SCENARIO_POLL_S)

    # --- time (the helpers of fieldtwin.testing, bound to this plant) ------------

    def now_s(self) -> float:
        return float(self.api.clock()["t_s"])

    def advance_to(self, t_s: float) -> None:
        from fieldtwin.testing.helpers import advance_to

        __tracebackhide__ = True
        advance_to(self, t_s)

    def run_until(
        self,
        predicate: Callable[[], object],
        *,
        within: float,
        show: Sequence[str] | None = None,
        wall_s: float | None = None,
    ) -> object:
        from fieldtwin.testing.helpers import run_until

        __tracebackhide__ = True
        target = RunningTarget(self, wall_s)
        return run_until(target, predicate, within=within, show=show)


@dataclass
class RunningTarget:
    """A running plant as the helpers see it: asked through its control API."""

    plant: RunningPlant
    wall_s: float | None = None
    label: str = field(init=False)

    def __post_init__(self) -> None:
        self.label = f"running plant {self.plant._plant_name()}"

    def now_s(self) -> float:
        return self.plant.now_s()

    def value(self, name: str) -> int:
        device, sep, obj = name.partition(":")
        try:
            if sep:
                return self.plant.api.peek(device.strip(), obj.strip())
            reply = self.plant.api.console(f"read {name}")
        except ControlError as exc:
            raise ConfigError(str(exc)) from None
        if reply.error is not None or not reply.lines:
            raise ConfigError(reply.error or f"read {name}: no answer")
        value = reply.lines[0].rpartition("= ")[2].strip()
        if value.upper().startswith("H'"):
            return int(value[2:].rstrip("'"), 16)
        return int(value)

    def _status(self, device: str | None) -> tuple[str, dict[str, Any]]:
        """(``"KIND DEVICE"``, the device's status) through the control API."""
        if device is None:
            raise ConfigError(f"{self.label}: name the device (e.g. '5' or 'tes1')")
        try:
            status = self.plant.api.status(device)
        except ControlError as exc:
            raise ConfigError(str(exc)) from None
        return f"{status['kind']} {device}", status

    def leds(self, device: str | None) -> tuple[str, dict[str, str]]:
        what, status = self._status(device)
        return what, {k: str(v) for k, v in status["leds"].items()}

    def state(self, device: str | None) -> tuple[str, str]:
        what, status = self._status(device)
        return what, str(status["state"])

    def default_show(self) -> list[str]:
        return []

    def advance_to(self, t_s: float) -> None:
        now = self.now_s()
        if t_s < now:
            raise ConfigError(
                f"cannot advance to t = {t_s:g} s: simulated time is already"
                f" {time_text(now)[4:]} and never goes back"
            )
        try:
            self.plant.api.run_until(t_s)
        except ControlError as exc:
            raise ConfigError(str(exc)) from None

    def run_until(
        self, predicate: Callable[[], object], within_s: float, step_s: float | None
    ) -> tuple[bool, object]:
        """Poll while the plant runs at its speed; the bound is simulated time, with a
        wall-clock bound as well (a paused clock never reaches it)."""
        clock = self.plant.api.clock()
        start = float(clock["t_s"])
        speed = clock.get("speed")
        pace = float(speed) if isinstance(speed, int | float) and speed > 0 else None
        wall = self.wall_s if self.wall_s is not None else 30.0 + 2 * within_s / (pace or 50.0)
        wall_end = time.monotonic() + wall
        while True:
            last = predicate()
            if last:
                return True, last
            now = self.now_s()
            if now - start >= within_s:
                return False, last
            if time.monotonic() > wall_end:
                raise ConfigError(
                    f"{self.label}: only {now - start:.3f} simulated s went by in"
                    f" {wall:g} wall s (paused clock?), waiting for {within_s:g} s"
                )
            interval = step_s / pace if step_s and pace else POLL_S
            time.sleep(min(max(interval, POLL_S), 1.0))


@contextlib.contextmanager
def start_plant(
    plant: str | Path | None = None,
    *,
    speed: float | str | None = None,
    args: Sequence[str] = (),
    start_s: float = START_S,
) -> Iterator[RunningPlant]:
    """``with start_plant("plant.toml") as running: ...``: a ``fieldtwin run`` on free
    ports, stopped when the block ends, however it ends."""
    running = RunningPlant(Path(plant) if plant is not None else None, speed=speed, args=args)
    try:
        running.start(start_s)
        yield running
    finally:
        running.stop()


@atexit.register
def stop_all() -> None:
    """Stop every plant still running (at exit, and when pytest ends its session)."""
    for running in list(_live):
        with contextlib.suppress(Exception):
            running.stop()
