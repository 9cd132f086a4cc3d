"""Unit level: a bus started with the observers' own process (fieldtwin.runtime.obslink).

What a wiretap's pump hands the bus is decoded in the child process; a remote
subscriber gets every event, in order, as the JSON text an in-process subscriber
would have sent; a subscriber with a small queue loses only its own oldest; the
process ends when the bus closes.  A bus whose process cannot start works as before.
"""

from __future__ import annotations

import json
import threading

from fieldtwin.modbus.model import Link
from fieldtwin.modbus.slave import SlaveSet
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.obslink import ObserversProcess
from fieldtwin.runtime.wiretap import Wiretap
from tests.trace.test_observers_thread import read_request, reply
from tests.trace.test_wiretap import FakeTes

WAIT_S = 30.0
REQUESTS = 500


def test_the_observers_process_decodes_in_order_and_a_small_queue_loses_its_own() -> None:
    bus = EventBus()
    bus.start(ObserversProcess.start)
    link = bus.link
    assert isinstance(link, ObserversProcess)
    texts: list[str] = []
    done = threading.Event()

    def drain() -> None:
        texts.extend(full.texts(100_000))
        if len(texts) >= 2 * REQUESTS:
            done.set()

    full = bus.subscribe(["modbus"], notify=drain, remote=True)
    small = bus.subscribe(["modbus"], maxlen=10, remote=True)  # read at the end only
    devices = [FakeTes(1, "A")]
    tap = Wiretap(bus, "tcp://x", "tcp", SlaveSet(devices, Link.TCP), None, "tcp://1.2.3.4:5")
    stream = tap.stream("c")
    in_process = EventBus()  # the same traffic decoded here, for comparison
    here = Wiretap(
        in_process, "tcp://x", "tcp", SlaveSet(devices, Link.TCP), None, "tcp://1.2.3.4:5"
    )
    mine = in_process.subscribe(["modbus"], maxlen=100_000)
    here_stream = here.stream("c")
    try:
        for n in range(REQUESTS):
            devices[0].powered = n % 2 == 0  # the state each request meets, taken at once
            for s in (stream, here_stream):
                s.seen_in(read_request(n), n)
                s.seen_out(reply(n), n)
        assert done.wait(WAIT_S), f"{len(texts)} events of {2 * REQUESTS}"
    finally:
        bus.close()
    assert link.proc.returncode == 0  # the process ended with the bus
    assert texts == mine.texts(100_000)  # byte for byte what this process would send
    events = [json.loads(text) for text in texts]
    assert [e["transaction"] for e in events] == [n for n in range(REQUESTS) for _ in (0, 1)]
    assert [e["tes"]["A"] for e in events[0::2][:2]] == ["answers", "powered_off"]
    assert len(small) <= 10 and small.dropped >= 2 * REQUESTS - 10 - len(small)
    assert len(small) + small.dropped == 2 * REQUESTS


def test_a_bus_whose_process_cannot_start_observes_on_its_thread() -> None:
    bus = EventBus()
    bus.start(lambda _: None)
    sub = bus.subscribe(["modbus"], remote=True)  # served here
    devices = [FakeTes(1, "A")]
    tap = Wiretap(bus, "tcp://x", "tcp", SlaveSet(devices, Link.TCP), None, "tcp://1.2.3.4:5")
    tap.stream("c").seen_in(read_request(7), 0)
    bus.close()
    assert [e.data["transaction"] for e in sub.take()] == [7]
