"""The ``[[module]]`` keys of a TSX SCM in a plant file.

    [[module]]
    type = "TSX SCM 2111"
    slot = 2
    adaptors = ["SCA1", "SCA1"]          # optional: override appendix 7.3
    faults = ["loopback_ch1"]            # optional: injected at start
    channels = [
      { channel = 0, endpoint = "pty", config = ["H'0802'", "H'9600'", 0, 0, 0, 0, 0, 0] },
      { channel = 1, loop = "point-to-point" },  # SCA2 only: PSR must then be 1
    ]

(an inline table stays on one line; ``[[module.channels]]`` tables take long entries)

``config`` is the write-configuration table (8 or 9 words, SCM 3.2), applied as
the request H'40' would be; a table the module would refuse is an error here.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from fieldtwin.devices.scm.faults import FAULTS
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.scm import config as cfgmod
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.module import ScmModule
from fieldtwin.tsx.scm.variants import Adaptor
from fieldtwin.words import plant_word, words_to_bytes

CHANNEL_KEYS = ("channel", "endpoint", "config", "signals", "loop")


Wiring = list[tuple[int, str, str]]  # (channel, endpoint URL, field path) to bind later


def configure_module(
    module: ScmModule, table: Mapping[str, Any], where: str, wiring: Wiring | None = None
) -> None:
    """The SCM keys.  With ``wiring``, channel endpoints are noted there for the runtime's
    binder (fieldtwin.runtime.binder) instead of being opened now."""
    rest = dict(table)
    if "adaptors" in rest:
        names = rest.pop("adaptors")
        if not isinstance(names, list):
            raise ConfigError(f"{where}.adaptors: a list of two adaptor names")
        module.adaptors = module._adaptors([str(n) for n in names])
        module.signals = [Signals(a) for a in module.adaptors]
        module.channels = [module._channel(i, module.configs[i]) for i in (0, 1)]
    for name in _list(rest.pop("faults", []), f"{where}.faults"):
        try:
            FAULTS.inject(module, str(name), True, {})
        except ConfigError as exc:
            raise ConfigError(f"{where}.faults: {exc}") from None
    channels = _list(rest.pop("channels", []), f"{where}.channels")
    for index, entry in enumerate(channels):
        _channel(module, entry, f"{where}.channels[{index}]", wiring)
    if rest:
        raise ConfigError(
            f"{where}: unknown key(s) {', '.join(sorted(rest))} for {module.type_name}"
            " (allowed: adaptors, faults, channels)"
        )
    module.changed()


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise ConfigError(f"{where}: must be a list")
    return value


def _channel(module: ScmModule, entry: Any, where: str, wiring: Wiring | None) -> None:
    if not isinstance(entry, Mapping):
        raise ConfigError(f'{where}: must be a table {{ channel = 0, endpoint = "pty" }}')
    unknown = sorted(set(entry) - set(CHANNEL_KEYS))
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown} (allowed: {', '.join(CHANNEL_KEYS)})")
    channel = entry.get("channel")
    if channel not in (0, 1):
        raise ConfigError(f"{where}.channel: {channel!r} not allowed (allowed 0 or 1)")
    if "config" in entry:
        _config(module, channel, entry["config"], f"{where}.config")
    if "loop" in entry:  # SCA2: "point-to-point" or "multipoint" (SCM 5.1 PSR)
        try:
            module.set_loop(channel, str(entry["loop"]))
        except ConfigError as exc:
            raise ConfigError(f"{where}.loop: {exc}") from None
    for name, level in dict(entry.get("signals", {})).items():
        try:
            module.set_signal(channel, str(name), level)
        except ConfigError as exc:
            raise ConfigError(f"{where}.signals: {exc}") from None
    if "endpoint" in entry and wiring is not None and str(entry["endpoint"]) != "memory":
        wiring.append((channel, str(entry["endpoint"]), f"{where}.endpoint"))
    elif "endpoint" in entry:
        try:
            module.attach(channel, str(entry["endpoint"]))
        except ConfigError as exc:
            raise ConfigError(f"{where}.endpoint: {exc}") from None


def _config(module: ScmModule, channel: int, value: Any, where: str) -> None:
    words = [plant_word(v, f"{where}[{i}]") for i, v in enumerate(_list(value, where))]
    fd_allowed = channel == 1 and module.variant.full_duplex_ch1
    try:
        config = cfgmod.decode(words_to_bytes(words), channel, fd_allowed)
        other = module.configs[1 - channel]
        if other is not None and cfgmod.speed_conflict(config.baud, other.baud):
            raise cfgmod.Refused("speed restriction with the other channel (SCM 3.2)")
    except cfgmod.Refused as exc:
        raise ConfigError(f"{where}: the module would refuse this table: {exc}") from None
    module.apply_config(channel, config, module.clock.now)


__all__ = ["Adaptor", "configure_module", "signal_text"]


def signal_text(module: ScmModule, channel: int, text: str) -> None:
    """The channel form of an SCM input: ``CTS=0`` (an adaptor signal) or ``loop=multipoint``."""
    name, sep, level = text.partition("=")
    if sep and name.strip().lower() == "loop":
        module.set_loop(channel, level)
        return
    if not sep or level.strip() not in ("0", "1"):
        raise ConfigError(
            f"SCM input {text!r}: write SIGNAL=0 or SIGNAL=1 (e.g. CTS=0),"
            " or loop=point-to-point / loop=multipoint (SCA2)"
        )
    module.set_signal(channel, name, int(level))
