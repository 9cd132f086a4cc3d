"""The character format of a TES serial port (§3.1.3, §3.1.4).

"Speed and parity are parameters; the number of data bits is set at 8 and the
number of stop bits is set to 1."  An endpoint that declares another number of
data or stop bits cannot reach a TES: it is refused, like a speed or parity
that differs from the TES's own.
"""

from __future__ import annotations

from typing import Protocol

from fieldtwin.errors import ConfigError

DATA_BITS = 8  # §3.1.3 fixed
STOP_BITS = 1  # §3.1.3 fixed


class CharacterFormat(Protocol):
    """What a line's settings say about its characters (transports' LineSettings)."""

    @property
    def data_bits(self) -> int: ...

    @property
    def stop_bits(self) -> int: ...


def check_fixed_format(settings: CharacterFormat | None) -> None:
    """ConfigError when ``settings`` name other data or stop bits than a TES has."""
    if settings is None:
        return
    if settings.data_bits != DATA_BITS:
        raise ConfigError(
            f"data={settings.data_bits} not allowed: a TES port has {DATA_BITS} data bits"
            f" (fixed, §3.1.3; allowed data={DATA_BITS})"
        )
    if settings.stop_bits != STOP_BITS:
        raise ConfigError(
            f"stop={settings.stop_bits} not allowed: a TES port has {STOP_BITS} stop bit"
            f" (fixed, §3.1.3; allowed stop={STOP_BITS})"
        )
