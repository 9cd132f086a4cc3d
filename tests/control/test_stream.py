"""A slow event-stream subscriber loses its oldest events; the publisher never waits."""

from __future__ import annotations

import asyncio
from typing import Any

from fieldtwin.control.stream import _pump, _Wakeup
from fieldtwin.runtime.events import EventBus


class StuckSocket:
    """A WebSocket whose peer never reads: the first send never completes."""

    def __init__(self) -> None:
        self.sent: list[Any] = []
        self.hang = asyncio.Event()

    async def receive(self) -> dict[str, str]:
        await asyncio.Event().wait()  # the peer says nothing
        return {"type": "websocket.disconnect"}

    async def send_json(self, data: Any) -> None:
        self.sent.append(data)
        await self.hang.wait()


def test_a_subscriber_that_does_not_read_is_bounded_and_never_slows_the_publisher() -> None:
    async def scenario() -> tuple[int, int, int, int]:
        bus = EventBus()
        wakeup = _Wakeup(asyncio.get_running_loop())
        sub = bus.subscribe(maxlen=100, notify=wakeup)
        socket = StuckSocket()
        task = asyncio.ensure_future(_pump(socket, sub, wakeup))  # type: ignore[arg-type]
        bus.publish(0, "object", "5", {"n": 0})
        for _ in range(100):  # the pump wakes and blocks in its first send
            if socket.sent:
                break
            await asyncio.sleep(0)
        for n in range(1, 100_001):  # the plant publishes on: nothing waits for the peer
            bus.publish(n, "object", "5", {"n": n})
        queued, dropped, sent = len(sub), sub.dropped, len(socket.sent)
        task.cancel()
        sub.close()
        return queued, dropped, sent, bus.published

    queued, dropped, sent, published = asyncio.run(scenario())
    assert published == 100_001
    assert sent == 1  # stuck in its first send
    assert queued == 100  # memory bounded by the subscription's queue
    assert dropped >= 100_000 - 100  # the oldest were dropped and counted


def test_a_subscriber_is_told_how_many_it_lost() -> None:
    async def scenario() -> list[Any]:
        bus = EventBus()
        wakeup = _Wakeup(asyncio.get_running_loop())
        sub = bus.subscribe(maxlen=3, notify=wakeup)
        socket = StuckSocket()
        socket.hang.set()  # this peer reads
        for n in range(10):
            bus.publish(n, "clock", "clock", {"n": n})
        task = asyncio.ensure_future(_pump(socket, sub, wakeup))  # type: ignore[arg-type]
        for _ in range(100):
            if len(socket.sent) >= 4:
                break
            await asyncio.sleep(0)
        task.cancel()
        return socket.sent

    sent = asyncio.run(scenario())
    assert sent[0] == {"kind": "dropped", "count": 7}
    assert [event["n"] for event in sent[1:]] == [7, 8, 9]
