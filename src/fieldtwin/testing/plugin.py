"""The pytest plugin of fieldtwin (entry point ``pytest11``: loaded once fieldtwin is installed).

Fixtures: ``plant``, ``plc``, ``tes`` (in process, on the simulated clock),
``running_plant`` (a real ``fieldtwin run`` subprocess), ``advance_to`` and
``run_until`` (the time helpers bound to the test's plant).  Marker:
``@pytest.mark.plant("file.toml", tes=2, speed=10, args=[...])``.  docs/testing.md.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import Tes
from fieldtwin.plant import Plant, build_plant, read_plant
from fieldtwin.testing import helpers
from fieldtwin.testing.process import PlantStartError, RunningPlant
from fieldtwin.tsx.plc import Plc

MARKER = (
    "plant(path=None, *, tes=None, speed=None, args=()): the plant file the fixtures plant,"
    " plc, tes and running_plant bring to life (relative to the test file, then to the"
    " rootdir; none: the embedded default plant); tes: the slave number the tes fixture"
    " gives; speed: the running plant's --speed; args: more `fieldtwin run` options"
)
MARKER_KEYS = ("tes", "speed", "args")
_RUNNING = pytest.StashKey[RunningPlant]()
_SESSION_RUNS = pytest.StashKey[set[RunningPlant]]()  # the plants this session started


@dataclass(frozen=True, slots=True)
class PlantSpec:
    """What the marker (or an indirect parameter) asks for."""

    path: Path | None
    tes: int | None = None
    speed: float | str | None = None
    args: tuple[str, ...] = field(default_factory=tuple)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", MARKER)
    config.stash[_SESSION_RUNS] = set()


def pytest_unconfigure(config: pytest.Config) -> None:
    """A run an interrupted session left (its fixture's teardown never ran) ends too."""
    runs: set[RunningPlant] = config.stash.get(_SESSION_RUNS, set())
    for running in list(runs):
        running.stop()


def _resolve(request: pytest.FixtureRequest, value: object, where: str) -> Path:
    if not isinstance(value, str | Path) or not str(value):
        pytest.fail(f"{where}: {value!r} is not a plant file path", pytrace=False)
    path = Path(value)
    if path.is_absolute():
        tried = [path]
    else:
        tried = [request.path.parent / path, request.config.rootpath / path]
    for candidate in tried:
        if candidate.is_file():
            return candidate
    pytest.fail(
        f"{where}: no plant file {str(value)!r} (looked for {', '.join(map(str, tried))})",
        pytrace=False,
    )


def plant_spec(request: pytest.FixtureRequest) -> PlantSpec:
    """The plant of this test: an indirect parameter of ``plant``, else the closest
    ``plant`` marker, else the embedded default plant."""
    marker = request.node.get_closest_marker("plant")
    where = f"{request.node.nodeid}: @pytest.mark.plant"
    kwargs: dict[str, Any] = dict(marker.kwargs) if marker is not None else {}
    unknown = sorted(set(kwargs) - set(MARKER_KEYS))
    if unknown:
        pytest.fail(
            f"{where}: unknown keyword(s) {', '.join(unknown)} (allowed: {', '.join(MARKER_KEYS)})",
            pytrace=False,
        )
    args = marker.args if marker is not None else ()
    if len(args) > 1:
        pytest.fail(f"{where}: one plant file at most, got {len(args)}", pytrace=False)
    value: object = args[0] if args else None
    param = getattr(request, "param", None) if request.fixturename == "plant" else None
    if param is not None:
        value, where = param, f"{request.node.nodeid}: plant parameter"
    path = _resolve(request, value, where) if value is not None else None
    tes = kwargs.get("tes")
    if tes is not None and (isinstance(tes, bool) or not isinstance(tes, int)):
        pytest.fail(f"{where}: tes={tes!r} is not a slave number", pytrace=False)
    extra = kwargs.get("args", ())
    if isinstance(extra, str) or not all(isinstance(a, str) for a in extra):
        pytest.fail(f"{where}: args={extra!r} is not a list of strings", pytrace=False)
    return PlantSpec(path, tes, kwargs.get("speed"), tuple(extra))


@pytest.fixture
def plant(request: pytest.FixtureRequest) -> Iterator[Plant]:
    """The test's plant, built on the simulated clock: no endpoint is opened, time
    moves only when the test advances it (``plant.plc.advance``, ``advance_to``...)."""
    spec = plant_spec(request)
    try:
        built = build_plant(
            read_plant(spec.path), speed=None if spec.speed is None else _speed(spec.speed)
        )
    except ConfigError as exc:
        pytest.fail(f"plant fixture: {exc}", pytrace=False)
    try:
        yield built
    finally:
        built.close()
        runner = built.plc.runner if built.plc is not None else None
        stop = getattr(runner, "stop", None)
        if callable(stop):  # a test wired a real endpoint: its transports are closed
            stop()


def _speed(value: object) -> float | None:
    if value == "max":
        return None
    if isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
        return float(value)
    pytest.fail(
        f"@pytest.mark.plant: speed={value!r} (allowed a number > 0 or 'max')", pytrace=False
    )


@pytest.fixture
def plc(plant: Plant) -> Plc:
    """The PLC of the test's plant."""
    if plant.plc is None:
        pytest.fail(
            f"plc fixture: {plant.name} has no PLC (no [plc] and no [[module]])", pytrace=False
        )
    return plant.plc


@pytest.fixture
def tes(request: pytest.FixtureRequest, plant: Plant) -> Tes:
    """A TES of the test's plant: the first in file order, or the marker's ``tes=N``."""
    spec = plant_spec(request)
    if not plant.tes:
        pytest.fail(f"tes fixture: {plant.name} has no [[tes]]", pytrace=False)
    if spec.tes is None:
        return plant.tes[0]
    try:
        return plant.tes_by_slave(spec.tes)
    except ConfigError as exc:
        pytest.fail(f"tes fixture: {plant.name}: {exc}", pytrace=False)


@pytest.fixture
def running_plant(request: pytest.FixtureRequest) -> Iterator[RunningPlant]:
    """``fieldtwin run`` of the test's plant in a subprocess, its TCP endpoints and its
    control API on free ports; stopped after the test however it ends; its output is
    added to the report of a failing test."""
    spec = plant_spec(request)
    running = RunningPlant(spec.path, speed=spec.speed, args=spec.args)
    request.node.stash[_RUNNING] = running
    runs = request.config.stash.setdefault(_SESSION_RUNS, set())
    runs.add(running)
    try:
        try:
            running.start()
        except (PlantStartError, ConfigError) as exc:
            pytest.fail(f"running_plant fixture: {exc}", pytrace=False)
        yield running
    finally:
        running.stop()
        runs.discard(running)


def _time_target(request: pytest.FixtureRequest) -> object:
    if "running_plant" in request.fixturenames:
        return request.getfixturevalue("running_plant")
    return request.getfixturevalue("plant")


@pytest.fixture
def advance_to(request: pytest.FixtureRequest) -> Callable[[float], None]:
    """``advance_to(t)``: the test's plant (the running plant if the test has one) to
    simulated time ``t`` seconds."""
    target = _time_target(request)

    def advance(t_s: float) -> None:
        __tracebackhide__ = True
        helpers.advance_to(target, t_s)

    return advance


@pytest.fixture
def run_until(request: pytest.FixtureRequest) -> Callable[..., Any]:
    """``run_until(predicate, within=seconds, show=[...])`` on the test's plant."""
    target = _time_target(request)

    def run(predicate: Callable[[], object], *, within: float, **options: Any) -> object:
        __tracebackhide__ = True
        return helpers.run_until(target, predicate, within=within, **options)

    return run


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    running = item.stash.get(_RUNNING, None)
    if running is not None and report.failed and running.command:
        report.sections.append((f"fieldtwin run ({report.when})", running.output()))
    return report
