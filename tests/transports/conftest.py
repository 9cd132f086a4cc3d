"""One connected pair per backend, for the conformance suite (DESIGN rule 5)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from fieldtwin.transports.base import Transport
from fieldtwin.transports.memory import memory_pair
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from fieldtwin.transports.tcp import connect, listen


@dataclass
class Pair:
    backend: str
    a: Transport  # the end under test
    b: Transport  # its peer
    peer_close_seen: bool  # does ``a`` notice ``b`` closing?


def _tcp_pair() -> tuple[Transport, Transport]:
    listener = listen()
    try:
        b = connect(*listener.address)
        end = time.monotonic() + 5.0
        while (a := listener.accept()) is None:
            assert time.monotonic() < end, "no connection accepted within 5 s"
        return a, b
    finally:
        listener.close()


def _make(backend: str) -> Pair:
    if backend == "memory":
        left, right = memory_pair()
        return Pair(backend, left, right, peer_close_seen=True)
    if backend == "pty":
        # our pty master, and a pyserial-opened peer on its slave path
        master = open_pty()
        assert master.peer_path is not None
        return Pair(backend, master, open_serial(master.peer_path), peer_close_seen=False)
    if backend == "serial":
        # our serial backend on a pty slave ("a serial device"); the master is its peer
        master = open_pty()
        assert master.peer_path is not None
        return Pair(backend, open_serial(master.peer_path), master, peer_close_seen=True)
    a, b = _tcp_pair()
    return Pair(backend, a, b, peer_close_seen=True)


@pytest.fixture(params=["memory", "pty", "tcp", "serial"])
def pair(request: pytest.FixtureRequest) -> Iterator[Pair]:
    made = _make(request.param)
    try:
        yield made
    finally:
        made.a.close()
        made.b.close()
