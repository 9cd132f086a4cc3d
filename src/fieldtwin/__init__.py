"""fieldtwin: executable twins of legacy field I/O hardware.

TSX Series 7 intelligent modules (AEM 811, DEM 2412/2413, SCM 20/21/22) on a
simulated PLC bus, and Leroy TES remote I/O terminals as Modbus slaves.
"""

import importlib
import importlib.abc
import importlib.machinery
import sys
import types

from fieldtwin import hosting
from fieldtwin.errors import ConfigError, FieldtwinError, ProtocolError, TransportError

# The Python library's composition root: a core that needs the OS (a pty wired in a
# script) gets it from this module, loaded on first use (docs/architecture.md, "Façade").
hosting.install("fieldtwin.facade.host")

# Documented names whose module moved above the cores: the old path keeps working,
# loaded only when imported (docs/decisions.md, "Glue out of the cores").
MOVED = {"fieldtwin.tes.plant": "fieldtwin.facade.tes"}


class _MovedLoader(importlib.abc.Loader):
    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> None:
        return None

    def exec_module(self, module: types.ModuleType) -> None:
        target = importlib.import_module(self.new)
        names = getattr(target, "__all__", [n for n in vars(target) if not n.startswith("_")])
        module.__dict__.update({name: getattr(target, name) for name in names})
        module.__dict__["__all__"] = list(names)
        module.__doc__ = f"Moved to {self.new} (this path keeps working)."


class _MovedFinder(importlib.abc.MetaPathFinder):
    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        new = MOVED.get(fullname)
        return None if new is None else importlib.machinery.ModuleSpec(fullname, _MovedLoader(new))


if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
    sys.meta_path.append(_MovedFinder())

__all__ = ["MOVED", "ConfigError", "FieldtwinError", "ProtocolError", "TransportError"]


def _version() -> str:
    """The version, from one place: pyproject.toml (the installed distribution's
    metadata; in a checkout not installed, the file itself)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("fieldtwin")
    except PackageNotFoundError:
        import tomllib
        from pathlib import Path

        pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
        try:
            return str(tomllib.loads(pyproject.read_text("utf-8"))["project"]["version"])
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "0+unknown"


__version__ = _version()
