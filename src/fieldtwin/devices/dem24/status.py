"""The TSX DEM 2412 / 2413's lines for the console's ``status`` and the live view."""

from __future__ import annotations

from fieldtwin.tsx.dem24.module import Dem24


def details(mod: Dem24) -> dict[str, str]:
    """Time base, stack, logging, inputs: the DEM's own status lines."""
    tb = mod.timebase
    now = mod.clock.now
    osc = [i for i, d in enumerate(mod.detectors or []) if d.oscillating]
    return {
        "time": f"{tb.now(now)} ({tb.state.value})" if tb.ready else tb.state.value,
        "sync fault": "yes" if tb.fault else "no",
        "stack": f"{len(mod.stack)}/{mod.stack.size} (lost {mod.stack.total_lost})",
        "logging": "active" if mod.logging else "stopped",
        "selected": f"H'{mod.selected():06X}'",
        "inputs": f"H'{mod.inputs.levels():06X}'",
        "oscillating": ", ".join(map(str, osc)) or "none",
        "config": "default" if mod.default_config else "user",
    }


def lines(mod: Dem24) -> dict[str, str]:
    """Every status line: the module's own, then the DEM's."""
    return {**mod.status(), **details(mod)}
