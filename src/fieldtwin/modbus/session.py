"""A Modbus TCP server session: MBAP frames in, replies out, by unit id.

One session per TCP connection; the slaves behind it are shared.  Unit id 0
is a broadcast (the server stands for a gateway to a TES line, TES 7.2.6);
unit id FFh reaches the only device when there is one (Modbus TCP 4.4.2); a
unit id no device answers to gets exception 0Bh, "gateway target device
failed to respond".  A stream that cannot be resynchronised closes the session.

The fused path (issue 25 item 2): a chunk of whole frames, the usual case, is cut
in place (no ``MbapFrame``), the request PDUs of reads and single writes are
decoded once per distinct PDU (the typed requests are frozen: one object serves
every poll of the same span), and the replies to word reads and word writes are
packed header and all with one ``struct`` call.  The same bytes as the general
path (``fused = False``), the same device calls in the same order, the same
counters: ``tests/modbus/test_fused_path.py`` runs both over random requests,
valid and not, exceptions and odd chunks included.  A device with a
``fused_exchange`` (a TES) is asked once per request instead of four times
(``tests/tes/test_read_plan.py``), and a well-formed fc 16 request is decoded in place.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from functools import cache
from typing import Protocol

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.mbap import (
    HEADER,
    MAX_LENGTH,
    MIN_LENGTH,
    MODBUS_PROTOCOL,
    MbapDecoder,
    MbapFrame,
    encode_mbap,
)
from fieldtwin.modbus.model import (
    Counter,
    Link,
    NoReply,
    ReadWords,
    Request,
    Result,
    SlaveDevice,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.pdu import (
    MAX_WRITE_WORDS,
    WRITE_REGISTERS,
    Rejection,
    decode_request,
    encode_exception,
    encode_response,
)
from fieldtwin.modbus.slave import BROADCAST, Outbox, SlaveSet, Transmission, _counter_for

SERVER_UNIT = 0xFF
GATEWAY_TARGET_FAILED = 0x0B

_HEAD = struct.Struct(">HHHB")  # transaction, protocol, length, unit
_WRITE_HEAD = struct.Struct(">HHB")  # fc 16: address, quantity, byte count
# decoded request PDUs kept per session (reads and single writes: 5 bytes each); a
# master polls a few spans over and over, so the set stays small; bounded all the same
REQUEST_CACHE = 256
_CACHED_FUNCTIONS = frozenset((1, 2, 3, 4, 5, 6))
_FRAMES_EXECUTED = Counter.FRAMES_EXECUTED
_EXCEPTION_REPLIES = Counter.EXCEPTION_REPLIES
_NOT_READY_REPLIES = Counter.NOT_READY_REPLIES
_GOOD_FRAMES = Counter.GOOD_FRAMES


class FusedExchange(Protocol):
    """A device's request in one call (``fused_exchange``, an optional ability): what
    ``count(GOOD_FRAMES)``, ``execute``, ``count`` of the reply's counter and
    ``answer_delay`` do, in that order; the result and the reply's instant, or None
    when the device stays silent (only the frame counted)."""

    def __call__(self, request: Request, link: Link, now: int, /) -> tuple[Result, int] | None: ...


@cache
def _words(count: int) -> struct.Struct:
    """``count`` big-endian words: the values of an fc 16 request."""
    return struct.Struct(f">{count}H")


@cache
def _read_reply(count: int) -> struct.Struct:
    """MBAP header, function, byte count and ``count`` words: one read reply."""
    return struct.Struct(f">HHHBBB{count}H")


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
        # the fused path (False: every frame through the general one, the reference)
        self.fused = True
        # unit id -> device: the slave numbers are fixed when the set is made
        self._units: dict[int, SlaveDevice] = dict(self.slaves.by_number)
        if SERVER_UNIT not in self._units and len(self.slaves.devices) == 1:
            self._units[SERVER_UNIT] = self.slaves.devices[0]
        self._requests: dict[bytes, Request | Rejection] = {}
        # unit id -> the device's fused exchange, for devices that have one (a TES)
        self._exchanges: dict[int, FusedExchange] = {}
        for unit, device in self._units.items():
            exchange = getattr(device, "fused_exchange", None)
            if exchange is not None:
                self._exchanges[unit] = exchange
        # the outbox's heap and the decoder's partial frame, read without a call per request
        self._held = self._outbox.heap
        self._partial = self._decoder.partial

    @property
    def closed(self) -> bool:
        return self.close_reason is not None

    def receive(self, data: bytes, now: int) -> None:
        """Bytes that arrived at ``now`` (call ``poll(now)`` next for due replies)."""
        if self.close_reason is not None:
            return
        if self.fused and not self._partial:
            # whole frames from the start, the usual case; a bad length anywhere in the
            # chunk goes the general way (it closes the session before any frame runs)
            size, end = len(data), 0
            while end + HEADER <= size:
                length = (data[end + 4] << 8) | data[end + 5]
                if not MIN_LENGTH <= length <= MAX_LENGTH:
                    end = -1
                    break
                if end + HEADER - 1 + length > size:
                    break
                end += HEADER - 1 + length
            if end > 0:
                start = 0
                while start < end:
                    start = self._fused(data, start, now)
                if end < size:
                    self._decoder.feed(data[end:])  # the start of the next frame
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
        if not self._held:
            return ready
        return ready + [transmission for transmission, _ in self._outbox.due(now)]

    def next_deadline(self) -> int | None:
        if self._ready:
            return self._ready[0].at  # never later than anything in the outbox
        held = self._held
        return held[0].at if held else None

    def _put(self, at: int, data: bytes, now: int, device: SlaveDevice | None = None) -> None:
        if at <= now and not self._outbox:
            self._ready.append(Transmission(at, data))
        else:
            self._outbox.put(at, data, device)

    def _fused(self, data: bytes, start: int, now: int) -> int:
        """The frame at ``start`` of ``data`` (whole, its length checked): what ``_frame``
        does, with no frame object and, for word reads and writes, one ``pack``; the
        offset of the next frame.  A device with a ``fused_exchange`` (a TES) does its
        bookkeeping in that one call; the request is decoded first (nothing a device
        sees), a rejection counted as ever."""
        transaction, protocol, length, unit = _HEAD.unpack_from(data, start)
        first: int = start + HEADER
        end: int = first + length - 1
        device = self._units.get(unit)
        if device is None or protocol != MODBUS_PROTOCOL:
            self._frame(MbapFrame(transaction, unit, data[first:end], protocol), now)
            return end
        link = self.link
        pdu = data[first:end]
        request: Request | Rejection | None
        if end - first == 5 and data[first] in _CACHED_FUNCTIONS:
            requests = self._requests
            request = requests.get(pdu)
            if request is None:
                request = decode_request(pdu)
                if len(requests) >= REQUEST_CACHE:
                    requests.clear()
                requests[pdu] = request
        elif data[first] == WRITE_REGISTERS and end - first >= 6:
            # fc 16 as decode_request makes it, when well formed (its values change
            # from one write to the next: not kept)
            address, count, size = _WRITE_HEAD.unpack_from(data, first + 1)
            if 1 <= count <= MAX_WRITE_WORDS and address + count <= 0x10000:
                if size == 2 * count and end - first == 6 + size:
                    request = WriteWords(address, _words(count).unpack_from(data, first + 6))
                else:
                    request = decode_request(pdu)
            else:
                request = decode_request(pdu)
        else:
            request = decode_request(pdu)
        exchange = self._exchanges.get(unit)
        if isinstance(request, Rejection):
            device.count(link, _GOOD_FRAMES, now)
            device.count(link, _EXCEPTION_REPLIES, now)
            pdu = encode_exception(request.function, request.code)
            reply = encode_mbap(transaction, unit, pdu)
            at = now + device.answer_delay(link)
        else:
            if exchange is not None:
                done = exchange(request, link, now)
                if done is None:
                    return end
                result, at = done
            else:
                device.count(link, _GOOD_FRAMES, now)
                result = device.execute(request, link, now, False)
            kind = request.__class__
            if (
                kind is ReadWords and result.__class__ is tuple and len(result) == request.count  # type: ignore[union-attr]
            ):
                count = len(result)
                try:
                    head = (transaction, 0, 3 + 2 * count, unit, data[first], 2 * count)
                    reply = _read_reply(count).pack(*head, *result)
                except struct.error:  # not 16-bit words: the general encoder says what
                    reply = encode_mbap(transaction, unit, encode_response(request, result))
                counter = _FRAMES_EXECUTED
            elif result is None and (kind is WriteWords or kind is WriteWord):
                reply = _HEAD.pack(transaction, 0, 6, unit) + data[first : first + 5]  # the echo
                counter = _FRAMES_EXECUTED
            elif result.__class__ is NoReply:
                return end
            else:
                reply = encode_mbap(transaction, unit, encode_response(request, result))
                counter = _counter_for(result)
            if exchange is None:
                device.count(link, counter, now)
                at = now + device.answer_delay(link)
        if at <= now and not self._held:
            self._ready.append(Transmission(at, reply))
        else:
            self._outbox.put(at, reply, device)
        return end

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
