"""Observers off the simulation's thread: raw records in, events complete and in order out.

Unit level: a started bus (its observers' thread) decodes what a wiretap's pump hands
it, in order, and a slow subscriber loses only its own oldest events.  User level: a
real ``fieldtwin run``, a master sending N requests on several connections, and two
``/events`` subscribers (the client's batches, and one event per message) that each
see the 2N frames, each connection's in order.
"""

from __future__ import annotations

import socket
import struct
import threading
from collections import deque
from pathlib import Path

from fieldtwin.client import Client
from fieldtwin.modbus.model import Link
from fieldtwin.modbus.slave import SlaveSet
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.wiretap import Wiretap
from tests.control.plantproc import fieldtwin_run
from tests.trace.test_wiretap import FakeTes, mbap

WAIT_S = 30.0


def read_request(transaction: int) -> bytes:
    return mbap(transaction, 1, bytes.fromhex("0300000002"))


def reply(transaction: int) -> bytes:
    return mbap(transaction, 1, bytes.fromhex("030400010002"))


def test_a_started_bus_decodes_in_order_and_a_slow_subscriber_loses_its_oldest() -> None:
    bus = EventBus()
    bus.start()
    seen: list[int] = []
    decoded_on: set[str] = set()
    fast = bus.subscribe(["modbus"])
    slow = bus.subscribe(["modbus"], maxlen=10)  # never read until the end
    done = threading.Event()

    def drain() -> None:
        decoded_on.add(threading.current_thread().name)
        seen.extend(int(str(e.data["transaction"])) for e in fast.take(100_000))
        if len(seen) >= 2000:
            done.set()

    fast._notify = drain
    devices = [FakeTes(1, "A")]
    tap = Wiretap(bus, "tcp://x", "tcp", SlaveSet(devices, Link.TCP), None, "tcp://1.2.3.4:5")
    stream = tap.stream("c")
    try:
        for n in range(1000):
            devices[0].powered = n % 2 == 0  # the state each request meets, taken at once
            stream.seen_in(read_request(n), n)
            stream.seen_out(reply(n), n)
        assert done.wait(WAIT_S)
    finally:
        bus.close()
    assert seen == [n // 2 for n in range(2000)]  # every frame, in order
    assert decoded_on == {"fieldtwin-observers"}
    kept = slow.take()
    assert [e.data["transaction"] for e in kept] == [n // 2 for n in range(1990, 2000)]
    assert slow.dropped == 1990 and fast.dropped == 0
    states = [e.data["tes"] for e in kept if e.data["dir"] == "in"]
    assert states == [{"A": "powered_off"}, {"A": "answers"}] * 2 + [{"A": "powered_off"}]


def test_a_full_buffer_counts_what_it_lost_for_every_subscriber() -> None:
    bus = EventBus(feed=5)
    sub = bus.subscribe()
    bus._feed = deque()  # as start() leaves it, without the thread: nothing drains yet
    for n in range(8):
        bus.publish(n, "clock", "clock", {"n": n})
    assert bus.process() == 5
    assert [e.data["n"] for e in sub.take()] == [0, 1, 2, 3, 4]
    assert sub.dropped == 3


def _requests(port: int, first: int, count: int) -> None:
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        for transaction in range(first, first + count):
            sock.sendall(mbap(transaction, 1, struct.pack(">BHH", 3, 37, 10)))
            got = b""
            while len(got) < 9 + 20:
                chunk = sock.recv(4096)
                assert chunk, "the plant closed the connection"
                got += chunk
            assert got[:2] == transaction.to_bytes(2, "big")


def test_subscribers_see_every_frame_sent_in_order(tmp_path: Path) -> None:
    plant = tmp_path / "plant.toml"
    plant.write_text(
        '[plc]\nmodel = "TSX 87"\nscan_ms = 10\n'
        '[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:0"\n'
    )
    connections, each = 4, 500
    with fieldtwin_run(plant) as running, Client(running.url) as api:
        batched = api.events(["modbus"], timeout_s=WAIT_S)
        single = _single_stream(running.url)
        masters = [
            threading.Thread(target=_requests, args=(running.modbus_port, c * 10_000, each))
            for c in range(connections)
        ]
        for master in masters:
            master.start()
        for master in masters:
            master.join(WAIT_S * 2)
        total = 2 * connections * each
        for stream in (batched, single):
            events = [next(stream) for _ in range(total)]
            assert not any(e["kind"] == "dropped" for e in events)
            for c in range(connections):
                mine = [e for e in events if e["transaction"] // 10_000 == c]
                assert [(e["transaction"], e["dir"]) for e in mine] == [
                    (c * 10_000 + n, d) for n in range(each) for d in ("in", "out")
                ]
            stream.close()


def _single_stream(url: str) -> _Single:
    from websockets.sync.client import connect

    return _Single(connect(url.replace("http://", "ws://") + "/events?kind=modbus"))


class _Single:
    """The stream without ``batch``: one event per message (as websocat shows it)."""

    def __init__(self, connection: object) -> None:
        self._socket = connection.__enter__()  # type: ignore[attr-defined]

    def __next__(self) -> dict[str, object]:
        import json

        message = self._socket.recv(timeout=WAIT_S)  # type: ignore[attr-defined]
        item = json.loads(message)
        assert isinstance(item, dict)
        return item

    def close(self) -> None:
        self._socket.close()  # type: ignore[attr-defined]


def test_the_pcap_packets_are_the_bytes_dpkt_builds() -> None:
    import random

    from fieldtwin.runtime.pcap import dpkt_packet, tcp_packet

    rng = random.Random(26)
    for _ in range(2000):
        args = (
            (rng.randbytes(4), rng.randrange(65536)),
            (rng.randbytes(4), rng.randrange(65536)),
            rng.randrange(2**32),
            rng.randrange(2**32),
            rng.randrange(256),
            rng.randbytes(rng.randrange(0, 300)),
            rng.random() < 0.5,
        )
        assert tcp_packet(*args) == dpkt_packet(*args)
