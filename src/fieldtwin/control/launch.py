"""``fieldtwin run``'s control API: bind, start, announce, and close (docs/control.md)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from fieldtwin.control.guards import origin_of
from fieldtwin.control.observer import Observer
from fieldtwin.control.resources import Control
from fieldtwin.control.server import (
    DEFAULT_HOST,
    DEFAULT_PORT,
    ControlServer,
    bind_control,
    new_token,
)
from fieldtwin.control.sim import serve
from fieldtwin.control.trends import Trends
from fieldtwin.errors import ConfigError
from fieldtwin.plant import Plant
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.exposure import reachability
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.runner import Runner


@dataclass(slots=True)
class Launched:
    """A started control API: what to print, what to sample on each tick, how to stop."""

    server: ControlServer
    inbox: Inbox
    runner: Runner
    observer: Observer
    lines: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    withdraw: Callable[[], None] | None = None  # the door's control commands, withdrawn
    trends: Trends | None = None  # the series' rings, sampled on each tick (trends.py)

    @property
    def url(self) -> str:
        return self.server.url

    def close(self) -> None:
        self.runner.take_commands(None)
        self.server.close()
        self.inbox.close()
        if self.withdraw is not None:
            self.withdraw()


def launch(
    plant: Plant,
    runner: Runner,
    bus: EventBus,
    *,
    host: str | None,
    port: int | None,
    token: str | None,
    allow_origins: Sequence[str] = (),
) -> Launched:
    """Start the API on ``host``:``port`` (None: the default port, or any free one if busy).

    ``host`` None is 127.0.0.1 without a token; a host given (or a token given)
    requires a token on every request: ``token``, or a new one (printed).
    """
    if host is not None and token is None:
        token = new_token()
    if token is not None and not token.strip():
        raise ConfigError("--control-token: an empty token is not allowed")
    host = host or DEFAULT_HOST
    sock = bind_control(host, DEFAULT_PORT if port is None else port, fallback=port is None)
    inbox = Inbox(door=plant.door)  # commands are values the plant's door runs
    control = Control(plant, runner, bus)
    origins = check_origins(allow_origins)
    server = ControlServer(control, inbox, sock, token, allow_origins=origins)
    runner.take_commands(inbox)
    launched = Launched(server, inbox, runner, Observer(plant.devices, bus, plant.tags))
    launched.trends = control.trends
    launched.withdraw = serve(plant.door, control, control.console.handle)
    try:
        url = server.start()
    except BaseException:
        launched.close()
        raise
    launched.lines.append(f"control: {url}")
    page = f"{url}/" if token is None else f"{url}/?token={token}"
    launched.lines.append(f"dashboard: {page}")  # docs/dashboard.md
    attach = f"fieldtwin console --attach {url}"
    if token is not None:
        launched.lines.append(f"control token: {token}")
        attach += f" --token {token}"
    launched.lines.append(f"attach: {attach}")
    if port is None and not url.endswith(f":{DEFAULT_PORT}"):
        launched.warnings.append(
            f"warning: control port {DEFAULT_PORT} is in use; the control API listens on {url}"
        )
    launched.warnings.extend(exposure_warnings(host, url))
    return launched


def check_origins(given: Sequence[str]) -> list[str]:
    """``--allow-origin`` values: each a web origin (``http://host:port``), else ConfigError."""
    origins = []
    for text in given:
        origin = origin_of(text)
        if origin is None:
            raise ConfigError(
                f"--allow-origin {text!r}: not a web origin"
                " (allowed: http://HOST[:PORT] or https://HOST[:PORT], no path)"
            )
        origins.append(origin)
    return origins


def exposure_warnings(host: str, url: str) -> list[str]:
    """The warning naming the control listener when other machines can reach it."""
    why = reachability(host)
    if why is None:
        return []
    return [
        f"warning: control API {url} is reachable from other machines ({why});"
        " every request needs the control token"
    ]


__all__ = ["Launched", "check_origins", "exposure_warnings", "launch"]
