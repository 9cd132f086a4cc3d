"""Endpoint URLs: where a device is reachable, as written in a plant file or on the command line.

Pure parsing (a kernel module: plant glue below the transports may use it);
``fieldtwin.transports.url`` opens them.

Forms::

    memory                                  an in-memory pair (tests)
    pty                                     a new pseudo-terminal (peer opens its path)
    pty?baud=19200&parity=E                 ... with line settings for character timing
    tcp://127.0.0.1:5020                    Modbus TCP (MBAP) on a TCP port
    rtu+tcp://127.0.0.1:5021                Modbus RTU frames over a TCP socket
    serial:///dev/ttyUSB0?baud=38400&parity=E&data=8&stop=1
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import parse_qsl, urlsplit

from fieldtwin.charformat import CharFormat, line_settings
from fieldtwin.errors import ConfigError

LineSettings = CharFormat

FORMS = (
    "memory",
    "pty[?baud=..&parity=..&data=..&stop=..]",
    "tcp://HOST:PORT",
    "rtu+tcp://HOST:PORT",
    "serial:///DEVICE[?baud=..&parity=..&data=..&stop=..]",
)
SCHEMES = ("memory", "pty", "tcp", "rtu+tcp", "serial")
LINE_KEYS = ("baud", "parity", "data", "stop")


@dataclass(frozen=True, slots=True)
class Endpoint:
    """A parsed endpoint URL; fields that a scheme does not use are None."""

    scheme: str
    host: str | None = None
    port: int | None = None
    device: str | None = None
    settings: LineSettings | None = None

    @property
    def is_tcp(self) -> bool:
        return self.scheme in ("tcp", "rtu+tcp")

    def __str__(self) -> str:
        if self.is_tcp:
            host = f"[{self.host}]" if self.host and ":" in self.host else self.host
            return f"{self.scheme}://{host}:{self.port}"
        base = f"serial://{self.device}" if self.scheme == "serial" else self.scheme
        if self.settings is None:
            return base
        s = self.settings
        query = f"baud={s.baud}&parity={s.parity.letter}&data={s.data_bits}&stop={s.stop_bits}"
        return f"{base}?{query}"


def _bad(url: str, why: str) -> ConfigError:
    return ConfigError(f"endpoint {url!r}: {why}; allowed forms: {', '.join(FORMS)}")


def _int(url: str, key: str, text: str) -> int:
    # str.isdigit() is true for "²" and other digits int() refuses: ASCII only
    if not (text.isascii() and text.isdigit()):
        raise _bad(url, f"{key}={text!r} is not a whole number")
    return int(text)


def _line_settings(url: str, query: str) -> LineSettings | None:
    """baud/parity/data/stop query keys -> LineSettings (defaults for those not given)."""
    if not query:
        return None
    values: dict[str, int | str] = {}
    for key, value in parse_qsl(query, keep_blank_values=True):
        if key not in LINE_KEYS:
            raise ConfigError(
                f"endpoint {url!r}: unknown query key {key!r}; allowed keys: {', '.join(LINE_KEYS)}"
            )
        values[key] = value.upper() if key == "parity" else _int(url, key, value)
    default = line_settings()
    try:
        return line_settings(
            baud=int(values.get("baud", default.baud)),
            data_bits=int(values.get("data", default.data_bits)),
            parity=str(values.get("parity", default.parity.letter)),
            stop_bits=int(values.get("stop", default.stop_bits)),
        )
    except ConfigError as exc:
        raise ConfigError(f"endpoint {url!r}: {exc}") from None


def _tcp(url: str, scheme: str, rest: str) -> Endpoint:
    parts = urlsplit(f"{scheme}://{rest}")
    if parts.query or parts.fragment or parts.path not in ("", "/"):
        raise _bad(url, "a TCP endpoint is only HOST:PORT")
    try:
        port = parts.port
    except ValueError as exc:
        raise _bad(url, f"bad port ({exc})") from None
    if not parts.hostname or port is None:
        raise _bad(url, "a TCP endpoint needs a host and a port")
    return Endpoint(scheme, host=parts.hostname, port=port)


def _serial(url: str, rest: str) -> Endpoint:
    device, _, query = rest.partition("?")
    if not device.startswith("/") or device == "/":
        raise _bad(url, "a serial endpoint names a device path (serial:///dev/ttyUSB0)")
    return Endpoint("serial", device=device, settings=_line_settings(url, query) or line_settings())


def parse_endpoint(url: str) -> Endpoint:
    """Parse one of the FORMS; ConfigError naming the url and the forms otherwise."""
    text = url.strip()
    head, sep, rest = text.partition("://")
    if sep:
        if head in ("tcp", "rtu+tcp"):
            return _tcp(url, head, rest)
        if head == "serial":
            return _serial(url, rest)
        raise _bad(url, f"unknown scheme {head!r} (allowed: {', '.join(SCHEMES)})")
    name, _, query = text.partition("?")
    if name == "memory" and not query:
        return Endpoint("memory")
    if name == "pty":
        return Endpoint("pty", settings=_line_settings(url, query))
    raise _bad(url, "not an endpoint")
