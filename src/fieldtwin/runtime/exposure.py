"""Which listeners other machines can reach (issue 10 item 7).

Modbus has no authentication: a twin bound to ``0.0.0.0``, ``[::]`` or any
address that is not loopback lets every machine that can route to it read and
write the plant.  ``fieldtwin run`` prints the warnings of ``warnings_for`` next
to its ``listening:`` lines (tcp, rtu+tcp and SCM TCP endpoints alike).
"""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Iterable

from fieldtwin.errors import ConfigError
from fieldtwin.transports.url import parse_endpoint

_URL = re.compile(r"\b((?:rtu\+)?tcp://(?:\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]]+):\d+)")


def reachability(host: str) -> str | None:
    """Why ``host`` is reachable from other machines, or None when it is loopback only."""
    if host == "localhost":
        return None
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return f"host name {host!r} may resolve to an address other machines reach"
    if address.is_loopback:
        return None
    if address.is_unspecified:
        return "bound to every interface"
    return f"bound to {address}, not a loopback address"


def exposed(urls: Iterable[str]) -> list[tuple[str, str]]:
    """(url, why) for every tcp or rtu+tcp URL in ``urls`` (any text holding them)."""
    found: list[tuple[str, str]] = []
    for text in urls:
        for url in _URL.findall(text):
            try:
                host = parse_endpoint(url).host
            except ConfigError:
                continue
            why = None if host is None else reachability(host)
            if why is not None and (url, why) not in found:
                found.append((url, why))
    return found


def warnings_for(urls: Iterable[str]) -> list[str]:
    """One warning line per listener reachable from other machines (none: all loopback)."""
    return [
        f"warning: {url} is reachable from other machines ({why}); Modbus and raw TCP"
        " have no authentication: bind 127.0.0.1 or [::1] to keep it on this machine"
        for url, why in exposed(urls)
    ]


__all__ = ["exposed", "reachability", "warnings_for"]
