"""Endpoint URLs: the forms of fieldtwin.transports.url."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import PtyTransport
from fieldtwin.transports.serial import SerialTransport
from fieldtwin.transports.tcp import TcpListener
from fieldtwin.transports.url import Endpoint, open_endpoint, parse_endpoint
from tests.transports.transport_pumping import collect


@pytest.mark.parametrize(
    ("url", "endpoint"),
    [
        ("memory", Endpoint("memory")),
        ("pty", Endpoint("pty")),
        (" pty ", Endpoint("pty")),
        ("pty?baud=19200&parity=E", Endpoint("pty", settings=line_settings(19200, 8, "E", 1))),
        ("tcp://127.0.0.1:5020", Endpoint("tcp", host="127.0.0.1", port=5020)),
        ("tcp://localhost:502", Endpoint("tcp", host="localhost", port=502)),
        ("tcp://0.0.0.0:0", Endpoint("tcp", host="0.0.0.0", port=0)),
        ("tcp://[::1]:5020", Endpoint("tcp", host="::1", port=5020)),
        ("rtu+tcp://127.0.0.1:5021", Endpoint("rtu+tcp", host="127.0.0.1", port=5021)),
        (
            "serial:///dev/ttyUSB0",
            Endpoint("serial", device="/dev/ttyUSB0", settings=line_settings()),
        ),
        (
            "serial:///dev/ttyUSB0?baud=38400&parity=E&data=8&stop=1",
            Endpoint("serial", device="/dev/ttyUSB0", settings=line_settings(38400, 8, "E", 1)),
        ),
        (
            "serial:///dev/pts/7?data=7&parity=o&stop=2",
            Endpoint("serial", device="/dev/pts/7", settings=line_settings(9600, 7, "O", 2)),
        ),
    ],
)
def test_forms(url: str, endpoint: Endpoint) -> None:
    assert parse_endpoint(url) == endpoint


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("", r"endpoint '': not an endpoint; allowed forms: memory, pty"),
        ("udp://127.0.0.1:5020", r"unknown scheme 'udp'"),
        ("tcp://127.0.0.1", r"needs a host and a port"),
        ("tcp://:5020", r"needs a host and a port"),
        ("tcp://127.0.0.1:99999", r"bad port"),
        ("tcp://127.0.0.1:50x", r"bad port"),
        ("tcp://127.0.0.1:5020/x", r"only HOST:PORT"),
        ("tcp://127.0.0.1:5020?baud=1", r"only HOST:PORT"),
        ("serial://dev/ttyUSB0", r"names a device path"),
        ("serial:///dev/ttyUSB0?speed=9600", r"unknown query key 'speed'; allowed keys: baud"),
        ("serial:///dev/ttyUSB0?baud=fast", r"baud='fast' is not a whole number"),
        (
            "serial:///dev/ttyUSB0?parity=X",
            r"'serial:///dev/ttyUSB0\?parity=X': line setting parity",
        ),
        ("serial:///dev/ttyUSB0?data=6", r"data_bits=6: allowed 7 or 8"),
        ("pty?stop=3", r"stop_bits=3: allowed 1 or 2"),
        ("memory?baud=9600", r"not an endpoint"),
        ("ptyx", r"not an endpoint"),
    ],
)
def test_bad_urls_name_the_url_and_what_is_allowed(url: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_endpoint(url)


def test_is_tcp() -> None:
    assert parse_endpoint("rtu+tcp://127.0.0.1:1").is_tcp
    assert not parse_endpoint("pty").is_tcp


settings = st.builds(
    line_settings,
    baud=st.integers(1, 4_000_000),
    data_bits=st.sampled_from([7, 8]),
    parity=st.sampled_from(["N", "E", "O"]),
    stop_bits=st.sampled_from([1, 2]),
)
endpoints = st.one_of(
    st.just(Endpoint("memory")),
    st.builds(Endpoint, st.just("pty"), settings=st.none() | settings),
    st.builds(
        Endpoint,
        st.sampled_from(["tcp", "rtu+tcp"]),
        host=st.sampled_from(["127.0.0.1", "localhost", "::1", "plc-7.example"]),
        port=st.integers(0, 65535),
    ),
    st.builds(
        Endpoint,
        st.just("serial"),
        device=st.from_regex(r"/dev/[A-Za-z][A-Za-z0-9/_.-]{0,20}", fullmatch=True),
        settings=settings,
    ),
)


@given(endpoints)
def test_str_parses_back_to_the_same_endpoint(endpoint: Endpoint) -> None:
    assert parse_endpoint(str(endpoint)) == endpoint


def test_open_endpoint_opens_the_twins_side() -> None:
    pty = open_endpoint(parse_endpoint("pty?baud=19200&parity=E"))
    assert isinstance(pty, PtyTransport)
    assert pty.settings == line_settings(19200, 8, "E", 1)
    try:
        port = open_endpoint(parse_endpoint(f"serial://{pty.peer_path}?baud=19200&parity=E"))
        assert isinstance(port, SerialTransport)
        port.send(b"up")
        assert collect(pty, port, 2) == b"up"
        port.close()
    finally:
        pty.close()
    listener = open_endpoint(parse_endpoint("rtu+tcp://127.0.0.1:0"))
    assert isinstance(listener, TcpListener)
    assert listener.address[1] > 0
    listener.close()


def test_a_memory_endpoint_cannot_be_opened_alone() -> None:
    with pytest.raises(ConfigError, match="memory_pair"):
        open_endpoint(parse_endpoint("memory"))


@pytest.mark.parametrize("url", ["pty?baud=²", "pty?baud=١٢", "serial:///dev/ttyS0?stop=³"])
def test_unicode_digits_are_a_config_error_not_a_traceback(url: str) -> None:
    with pytest.raises(ConfigError, match=r"is not a whole number"):
        parse_endpoint(url)
