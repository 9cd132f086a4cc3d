"""The Python library's façade: the conveniences that need the OS, above the cores.

The sans-IO cores (tsx/, tes/) never import the runtime or the transports.  What
a Python user does by hand with real endpoints lives here, one layer above the
runtime: :mod:`.host` paces a ``Plc`` and opens an SCM channel's pty, serial
port or TCP listener (``scm.attach(0, "pty")``), :mod:`.tes` serves TES on their
Modbus endpoints (``start_tes_endpoints``).  docs/architecture.md, "Façade".
"""

from fieldtwin.facade.faults import fault_names, inject_fault

__all__ = ["fault_names", "inject_fault"]
