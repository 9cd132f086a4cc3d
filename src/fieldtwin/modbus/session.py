"""A Modbus TCP server session: MBAP frames in, replies out, by unit id.

One session per TCP connection; the slaves behind it are shared.  Unit id 0
is a broadcast (the server stands for a gateway to a TES line, TES 7.2.6);
unit id FFh reaches the only device when there is one (Modbus TCP 4.4.2); a
unit id no device answers to gets exception 0Bh, "gateway target device
failed to respond".  A stream that cannot be resynchronised closes the session.
"""

from __future__ import annotations

from collections.abc import Iterable

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.mbap import MODBUS_PROTOCOL, MbapDecoder, MbapFrame, encode_mbap
from fieldtwin.modbus.model import Counter, Link, SlaveDevice
from fieldtwin.modbus.pdu import encode_exception
from fieldtwin.modbus.slave import BROADCAST, Outbox, SlaveSet, Transmission

SERVER_UNIT = 0xFF
GATEWAY_TARGET_FAILED = 0x0B


class TcpSession:
    """Sans-IO Modbus TCP server side of one connection."""

    def __init__(self, devices: Iterable[SlaveDevice] | SlaveSet, link: Link = Link.TCP) -> None:
        self.slaves = devices if isinstance(devices, SlaveSet) else SlaveSet(devices, link)
        self.link = self.slaves.link
        self._decoder = MbapDecoder()
        self._outbox = Outbox()
        # replies due at once while the outbox is empty (answer delay 0): they skip the
        # outbox's heap; sent in the same order and at the same instant as through it
        self._ready: list[Transmission] = []
        self.close_reason: str | None = None

    @property
    def closed(self) -> bool:
        return self.close_reason is not None

    def receive(self, data: bytes, now: int) -> None:
        """Bytes that arrived at ``now`` (call ``poll(now)`` next for due replies)."""
        if self.closed:
            return
        try:
            frames = self._decoder.feed(data)
        except ProtocolError as exc:
            self.close_reason = str(exc)
            self._outbox.clear()
            self._ready.clear()
            return
        for frame in frames:
            self._frame(frame, now)

    def poll(self, now: int) -> list[Transmission]:
        """The replies due at or before ``now``."""
        ready = self._ready
        if ready:
            self._ready = []
        if not self._outbox:
            return ready
        return ready + [transmission for transmission, _ in self._outbox.due(now)]

    def next_deadline(self) -> int | None:
        if self._ready:
            return self._ready[0].at  # never later than anything in the outbox
        return self._outbox.next_deadline()

    def _put(self, at: int, data: bytes, now: int, device: SlaveDevice | None = None) -> None:
        if at <= now and not self._outbox:
            self._ready.append(Transmission(at, data))
        else:
            self._outbox.put(at, data, device)

    def _frame(self, frame: MbapFrame, now: int) -> None:
        if frame.protocol != MODBUS_PROTOCOL:
            return  # not Modbus: ignored
        if frame.unit == BROADCAST:
            self.slaves.count_all(Counter.GOOD_FRAMES, now)
            self.slaves.dispatch(BROADCAST, frame.pdu, now)
            return
        device = self._target(frame.unit)
        if device is None:
            pdu = encode_exception(frame.pdu[0], GATEWAY_TARGET_FAILED)
            self._put(now, encode_mbap(frame.transaction, frame.unit, pdu), now)
            return
        device.count(self.link, Counter.GOOD_FRAMES, now)
        reply = self.slaves.answer(device, frame.pdu, now)
        if reply is not None:
            data = encode_mbap(frame.transaction, frame.unit, reply.pdu)
            self._put(reply.at, data, now, device)

    def _target(self, unit: int) -> SlaveDevice | None:
        device = self.slaves.get(unit)
        if device is None and unit == SERVER_UNIT and len(self.slaves.devices) == 1:
            return self.slaves.devices[0]
        return device
