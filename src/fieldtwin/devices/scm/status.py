"""The TSX SCM's lines for the console's ``status``, the live view and ``fieldtwin run``."""

from __future__ import annotations

from fieldtwin.tsx.scm.module import ScmModule


def details(mod: ScmModule) -> dict[str, str]:
    """Activity, then one line a channel: adaptor, configuration, wiring, signals."""
    lines = {"activity": "executing a request" if mod.active else "awaiting a request"}
    for index, channel in enumerate(mod.channels):
        lost = mod.lines[index].overruns
        overrun = f" | {lost} characters lost (overrun)" if lost else ""
        wiring = mod.wiring.describe(index)
        lines[f"channel {index}"] = (
            f"{mod.adaptors[index].label} | {channel.describe()} | {wiring}"
            f" | {mod.signals[index].describe()}{overrun}"
        )
    if mod.app_name:
        lines["application name"] = mod.app_name.decode("latin-1").rstrip()
    return lines


def lines(mod: ScmModule) -> dict[str, str]:
    """Every status line: the module's own, then the SCM's."""
    return {**mod.status(), **details(mod)}


def endpoint_lines(mod: ScmModule) -> list[str]:
    """One ``listening:`` line per channel wired to a real endpoint (``fieldtwin run``)."""
    label = f"{mod.type_name} slot {mod.address}"
    return [
        f"listening: {label} channel {index} {port.describe()}"
        for index, port in enumerate(mod.wiring.ports)
        if port is not None and port.url != "memory"
    ]
