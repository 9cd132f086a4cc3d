"""The event stream: ``GET /events`` as a WebSocket over the plant's EventBus.

Query: ``kind=modbus,led`` and ``device=5,tes1`` (ids of ``GET /plant``, or
addresses) filter; ``queue=N`` (1..10000) bounds what may wait unread.  Each
message is one event as JSON (``{"t_s": ..., "kind": ..., "device": ..., ...}``);
with ``batch=1`` each message is a JSON array of the events that came together
(up to ``BATCH``, in order), which costs the plant's process far less per event
(fieldtwin.client and the dashboard ask for it).
A subscriber that does not keep up loses its oldest events (the bus's bounded
queue) and is told so by a ``{"kind": "dropped", "count": N}`` message (an item
of the array in a batch); it never slows the plant and never grows memory beyond
its queue (docs/control.md).  The events are built and encoded on the observers'
side (fieldtwin.runtime.events), each once however many subscribers send it: under
``fieldtwin run`` in the observers' own process, whose JSON texts are sent as they
come (fieldtwin.runtime.obslink).
"""

from __future__ import annotations

import asyncio
import threading
from typing import TYPE_CHECKING, Any

from fastapi import FastAPI, WebSocket, WebSocketDisconnect

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import DEFAULT_QUEUE, Subscription
from fieldtwin.runtime.obslink import RemoteSubscription

if TYPE_CHECKING:
    from fieldtwin.control.resources import Control
    from fieldtwin.control.sim import Sim

BATCH = 500  # events taken from the queue per wakeup
Texts = Subscription | RemoteSubscription  # events as JSON texts (the observers' process's)


def _split(text: str | None) -> list[str]:
    return [part.strip() for part in (text or "").split(",") if part.strip()]


class _Wakeup:
    """Called from the simulation's thread on each event: wakes the sender once."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop
        self.event = asyncio.Event()
        self._pending = False
        self._lock = threading.Lock()

    def __call__(self) -> None:
        with self._lock:
            if self._pending:
                return
            self._pending = True
        self.loop.call_soon_threadsafe(self._set)

    def _set(self) -> None:
        with self._lock:
            self._pending = False
        self.event.set()


def add_stream(app: FastAPI, control: Control, sim: Sim) -> None:
    def addresses(idents: list[str]) -> list[str] | None:
        if not idents:
            return None
        devices = control.devices()
        known = {str(d.address) for d in devices.values()}
        out = []
        for ident in idents:
            if ident in devices:
                out.append(str(devices[ident].address))
            elif ident in known or ident == "clock":
                out.append(ident)
            else:
                raise ConfigError(
                    f"device={ident!r}: no such device (allowed: {', '.join(devices)})"
                )
        return out

    @app.websocket("/events")
    async def events(websocket: WebSocket) -> None:
        params = websocket.query_params
        try:
            queue = int(params.get("queue", DEFAULT_QUEUE))
            if not 1 <= queue <= DEFAULT_QUEUE:
                raise ValueError
        except ValueError:
            await websocket.close(code=1008, reason=f"queue: allowed 1..{DEFAULT_QUEUE}")
            return
        batched = params.get("batch", "0")
        if batched not in ("0", "1"):
            await websocket.close(code=1008, reason="batch: allowed 0 or 1")
            return
        try:
            wanted = _split(params.get("device"))
            devices = await sim.call(lambda: addresses(wanted)) if wanted else None
        except ConfigError as exc:
            await websocket.close(code=1008, reason=str(exc)[:120])
            return
        wakeup = _Wakeup(asyncio.get_running_loop())
        try:
            sub = control.bus.subscribe(
                _split(params.get("kind")) or None,
                devices,
                maxlen=queue,
                notify=wakeup,
                remote=True,
            )
        except OverflowError as exc:
            await websocket.close(code=1013, reason=str(exc))
            return
        await websocket.accept()
        try:
            await _pump(websocket, sub, wakeup, batched == "1")
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass
        finally:
            sub.close()


async def _pump(websocket: WebSocket, sub: Texts, wakeup: _Wakeup, batched: bool = False) -> None:
    reader = asyncio.ensure_future(websocket.receive())  # a close from the peer ends us
    remote = isinstance(sub, RemoteSubscription)  # its events come as JSON texts
    dropped = 0
    try:
        while not reader.done():
            waiter = asyncio.ensure_future(wakeup.event.wait())
            await asyncio.wait({waiter, reader}, timeout=1.0, return_when="FIRST_COMPLETED")
            waiter.cancel()
            wakeup.event.clear()
            if reader.done():
                if reader.result().get("type") == "websocket.disconnect":
                    break
                reader = asyncio.ensure_future(websocket.receive())  # what it says is ignored
            while True:
                told: list[str] = []
                if sub.dropped != dropped:
                    lost, dropped = sub.dropped - dropped, sub.dropped
                    if batched:
                        told.append(f'{{"kind":"dropped","count":{lost}}}')
                    else:
                        await websocket.send_json({"kind": "dropped", "count": lost})
                batch: list[Any] = (
                    sub.texts(BATCH) if isinstance(sub, RemoteSubscription) else sub.take(BATCH)
                )
                if batched and (batch or told) and not reader.done():
                    told.extend(batch if remote else (event.json() for event in batch))
                    await websocket.send_text("[" + ",".join(told) + "]")
                if not batch or reader.done():
                    break
                if not batched:
                    for item in batch:  # a text is as send_json writes the event
                        if remote:
                            await websocket.send_text(item)
                        else:
                            await websocket.send_json(item.as_dict())
    finally:
        reader.cancel()


__all__ = ["add_stream"]
