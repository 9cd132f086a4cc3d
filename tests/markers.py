"""The `integration` marker, applied centrally, and the one-line summary of missing tools.

A test is `integration` when it starts a process, a browser or a socket server.  It
is found without editing the test: the test function, its fixtures and the module
functions they call (followed through the module's globals) are looked at for a
reference to one of the things that start such a thing (``subprocess``, ``socket``,
``pty``, Playwright, the real runner, the `running_plant` fixture ...).  What this
misses is caught when it runs: under ``-m "not integration"`` (``make test-fast``) a
test that spawns a process or binds a socket fails, saying to mark it
``@pytest.mark.integration``.
"""

from __future__ import annotations

import inspect
import re
import sys
import types
from collections.abc import Iterator
from typing import Any

import pytest

from tests.systools import SKIP_PREFIX

# The fixtures that bring up a real process or server (the pytest plugin's and ours).
FIXTURES = frozenset({"running_plant", "pytester", "testdir", "page", "browser"})
# Module names whose use means a process, a browser or a socket server.
MODULES = frozenset(
    {
        "subprocess",
        "socket",
        "socketserver",
        "pty",
        "select",
        "selectors",
        "serial",
        "playwright",
        "uvicorn",
        "websockets",
        "multiprocessing",
        "pexpect",
    }
)
# Names from fieldtwin and the tests' helpers that start one.
NAMES = frozenset(
    {
        "Popen",
        "fieldtwin_run",
        "sync_playwright",
        "ModbusTcpClient",
        "ModbusSerialClient",
        "openpty",
        "launch",
        "ControlServer",
        "bind_control",
        "start_server",
        "create_server",
        "serve",
        "run_plant",
        "open_endpoint",
        "RealTransports",
        "TcpListener",
        "listen",
        "bind",
        "serve_tcp",
        "serve_rtu_over_tcp",
        "start_plant",
        "start_endpoints",
    }
)
MAX_DEPTH = 6
_ALTERNATIVES = "|".join(sorted(MODULES))
_IMPORT = re.compile(rf"^\s*(?:import|from) (?:{_ALTERNATIVES})\b", re.M)


def _codes(code: types.CodeType) -> Iterator[types.CodeType]:
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes(const)


def _starts_something(func: Any, seen: set[int], depth: int = 0) -> bool:
    """Does ``func`` (or what it calls in its module) name a process/socket starter?"""
    func = inspect.unwrap(getattr(func, "__func__", func))
    inner = getattr(getattr(func, "hypothesis", None), "inner_test", None)
    if inner is not None:  # a @given test: look at the test itself
        func = inspect.unwrap(inner)
    code = getattr(func, "__code__", None)
    if code is None or id(code) in seen or depth > MAX_DEPTH:
        return False
    seen.add(id(code))
    env: dict[str, Any] = getattr(func, "__globals__", {})
    for part in _codes(code):
        names = set(part.co_names) | set(part.co_varnames)
        if names & NAMES:
            return True
        for name in part.co_names:
            value = env.get(name)
            if isinstance(value, types.ModuleType):
                root = value.__name__.split(".")[0]
                if root in MODULES or value.__name__ in MODULES:
                    return True
                continue
            if getattr(value, "__name__", None) in NAMES:
                return True
            if inspect.isfunction(value) and _starts_something(value, seen, depth + 1):
                return True
    return False


def _imports_inside(func: Any) -> bool:
    """``import subprocess`` (or another starter) inside the function itself."""
    try:
        source = inspect.getsource(func)
    except (OSError, TypeError):
        return False
    return _IMPORT.search(source) is not None


def is_integration(item: pytest.Item) -> bool:
    if item.get_closest_marker("integration") is not None:
        return True
    fixtures = set(getattr(item, "fixturenames", ()))
    if fixtures & FIXTURES:
        return True
    function = getattr(item, "function", None)
    if function is None:
        return False
    seen: set[int] = set()
    if _starts_something(function, seen) or _imports_inside(function):
        return True
    info = getattr(item, "_fixtureinfo", None)
    for name in fixtures:
        for fixturedef in info.name2fixturedefs.get(name, ()) if info else ():
            func = getattr(fixturedef, "func", None)
            module = getattr(func, "__module__", "") or ""
            if not module.startswith("tests"):
                continue  # pytest's own fixtures (tmp_path, capsys, monkeypatch ...)
            if _starts_something(func, seen) or _imports_inside(func):
                return True
    return False


def pytest_configure(config: pytest.Config) -> None:
    config.stash[_SKIPPED] = {}
    expr = config.getoption("markexpr", "") or ""
    if "not integration" in expr:
        _Guard.install()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("integration") is None and is_integration(item):
            item.add_marker(pytest.mark.integration)


class _Guard:
    """Under ``-m "not integration"``: a test that starts a process or binds a socket fails."""

    active: str | None = None
    installed = False
    EVENTS = frozenset({"subprocess.Popen", "os.posix_spawn", "os.fork", "socket.bind"})

    @classmethod
    def install(cls) -> None:
        if not cls.installed:
            sys.addaudithook(cls.hook)
            cls.installed = True

    @classmethod
    def hook(cls, event: str, args: tuple[Any, ...]) -> None:
        if cls.active is not None and event in cls.EVENTS:
            test, cls.active = cls.active, None  # said once; the test fails here
            raise RuntimeError(
                f"{test}: {event} in a test not marked integration (make test-fast runs"
                " no process or socket server): add @pytest.mark.integration"
            )


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item: pytest.Item) -> Iterator[None]:
    _Guard.active = item.nodeid if _Guard.installed else None
    try:
        return (yield)
    finally:
        _Guard.active = None


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Iterator[None]:
    _Guard.active = item.nodeid if _Guard.installed else None
    try:
        return (yield)
    finally:
        _Guard.active = None


_SKIPPED = pytest.StashKey[dict[str, int]]()


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if not report.skipped or not isinstance(report.longrepr, tuple):
        return
    reason = str(report.longrepr[2])
    if SKIP_PREFIX in reason:
        tool = reason.split(SKIP_PREFIX, 1)[1].strip()
        skipped = _CONFIG[0].stash[_SKIPPED] if _CONFIG else {}
        skipped[tool] = skipped.get(tool, 0) + 1


_CONFIG: list[pytest.Config] = []


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session: pytest.Session) -> None:
    _CONFIG[:] = [session.config]


def pytest_terminal_summary(terminalreporter: Any, config: pytest.Config) -> None:
    skipped = config.stash.get(_SKIPPED, {})
    if skipped:
        tools = sorted(skipped)
        count = sum(skipped.values())
        terminalreporter.write_line(
            f"{count} test{'' if count == 1 else 's'} skipped: missing {', '.join(tools)};"
            f" install with `sudo apt-get install -y {' '.join(tools)}` (make test does it"
            " when run as root on Debian; with CI=true they fail instead)",
            yellow=True,
        )
