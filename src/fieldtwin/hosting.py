"""Where the sans-IO cores find the world outside them, when a Python user asks for it.

A core never imports the runtime or the OS.  When a user of the Python library
wires a real endpoint by hand (``scm.attach(0, "pty")`` on a ``Plc`` built in a
script), the PLC core asks :func:`host` for what paces time and opens lines.
The package's root names the module that provides it (``install``), loaded on
first use only, the way python-can loads the interface a user names; a caller
may also hand a host to ``Plc(host=...)`` directly.  The plant file and
``fieldtwin run`` never come here: the runtime's binder opens their ports.
"""

from __future__ import annotations

import importlib

from fieldtwin.errors import ConfigError

_modules: list[str] = []


def install(module: str) -> None:
    """Name the module whose ``HOST`` serves the cores (the last one installed wins)."""
    _modules.append(module)


def host() -> object:
    """The installed host (its module imported now); ConfigError when none is installed."""
    if not _modules:
        raise ConfigError("a real endpoint needs a host (none installed; see fieldtwin.hosting)")
    return importlib.import_module(_modules[-1]).HOST


__all__ = ["host", "install"]
