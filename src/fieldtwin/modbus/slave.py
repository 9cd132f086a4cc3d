"""The slaves behind one line or server: dispatch, counters, answer delays (TES 7).

``SlaveSet`` decodes a request PDU for a slave number, asks the device to
execute it, counts what the TES count (TES 6.2.3.2) and builds the reply PDU.
``Outbox`` holds replies until their answer delay has passed.  Sans-IO: time is
an argument, replies come out as ``Transmission(at, data)``.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import NamedTuple

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import (
    LINE_COUNTERS,
    Counter,
    ExceptionCode,
    LineTally,
    Link,
    NoReply,
    PerLinkSlave,
    SharedLineCounts,
    SlaveDevice,
)
from fieldtwin.modbus.pdu import (
    WRITE_FUNCTIONS,
    Rejection,
    decode_request,
    encode_exception,
    encode_response,
)

BROADCAST = 0  # TES 7.2.6: "address to slave 0 = to all slaves"
FIRST_SLAVE = 1
LAST_SLAVE = 247
# TES 7 error codes: "4 = TES not ready" -- counted apart (TES 6.2.3.2 018h).
NOT_READY = ExceptionCode.SLAVE_DEVICE_FAILURE


class Transmission(NamedTuple):
    """Bytes to send at simulated time ``at`` (a named tuple: one per reply, cheap)."""

    at: int
    data: bytes


class Reply(NamedTuple):
    """A device's reply PDU, due at ``at``."""

    device: SlaveDevice
    pdu: bytes
    at: int


class SlaveSet:
    """Several slave devices sharing one link, dispatched by slave number."""

    def __init__(
        self, devices: Iterable[SlaveDevice], link: Link, shared_counts: bool = False
    ) -> None:
        self.link = link
        self.devices: tuple[SlaveDevice, ...] = tuple(devices)
        # shared_counts (an RTU line): the line-wide counters are counted once per frame
        # on a tally the devices that can read it share; the others count one by one
        self._tally: LineTally | None = None
        self._counting: tuple[SlaveDevice, ...] = self.devices
        self._by_number: dict[int, SlaveDevice] = {}
        for device in self.devices:
            number = slave_number(device, link)
            if not FIRST_SLAVE <= number <= LAST_SLAVE:
                raise ConfigError(f"slave number {number}: allowed {FIRST_SLAVE}..{LAST_SLAVE}")
            if number in self._by_number:
                raise ConfigError(f"slave number {number} is used twice on one {link.value} link")
            self._by_number[number] = device
        if not self.devices:
            raise ConfigError(f"no slave device on the {link.value} link")
        if shared_counts:
            tally = self._tally = LineTally()
            for device in self.devices:
                if isinstance(device, SharedLineCounts):
                    device.share_line_counts(link, tally)
            self._counting = tuple(d for d in self.devices if not isinstance(d, SharedLineCounts))

    @property
    def numbers(self) -> tuple[int, ...]:
        return tuple(sorted(self._by_number))

    def get(self, number: int) -> SlaveDevice | None:
        return self._by_number.get(number)

    @property
    def by_number(self) -> dict[int, SlaveDevice]:
        """Every device by its slave number (fixed when the set is made): a copy."""
        return dict(self._by_number)

    def count_all(self, counter: Counter, now: int, times: int = 1) -> None:
        """Every device on the link saw ``times`` more of ``counter``."""
        devices = self.devices
        if self._tally is not None and counter in LINE_COUNTERS:
            self._tally.counts[counter] += times  # once, for every device sharing it
            devices = self._counting
        for device in devices:
            for _ in range(times):
                device.count(self.link, counter, now)

    def dispatch(self, number: int, pdu: bytes, now: int) -> Reply | None:
        """Execute a request PDU for slave ``number``; the reply, or None when silent."""
        if number == BROADCAST:
            self._broadcast(pdu, now)
            return None
        device = self._by_number.get(number)
        if device is None:
            return None  # another slave's frame: not ours to answer
        return self.answer(device, pdu, now)

    def number_of(self, device: SlaveDevice) -> int:
        """The slave number ``device`` answers to on this link."""
        return slave_number(device, self.link)

    def answer(self, device: SlaveDevice, pdu: bytes, now: int) -> Reply | None:
        """Execute a request addressed to ``device``: its reply, or None if it stays silent."""
        link = self.link
        request = decode_request(pdu)
        if isinstance(request, Rejection):
            device.count(link, Counter.EXCEPTION_REPLIES, now)
            reply = encode_exception(request.function, request.code)
        else:
            result = device.execute(request, link, now, False)
            if isinstance(result, NoReply):
                return None
            reply = encode_response(request, result)
            device.count(link, _counter_for(result), now)
        return Reply(device, reply, now + device.answer_delay(link))

    def _broadcast(self, pdu: bytes, now: int) -> None:
        # TES 7.2.6: writes to slave 0 are executed by all, with no reply;
        # AMB-TES-29: broadcast reads are ignored.
        if not pdu or pdu[0] not in WRITE_FUNCTIONS:
            return
        request = decode_request(pdu)
        if isinstance(request, Rejection):
            return
        for device in self.devices:
            result = device.execute(request, self.link, now, True)
            if result is None:
                device.count(self.link, Counter.FRAMES_EXECUTED, now)


def slave_number(device: SlaveDevice, link: Link) -> int:
    """A device's slave number on ``link`` (TES 3.1.3 / 3.1.4: one per link)."""
    if isinstance(device, PerLinkSlave):
        return device.slave_for(link)
    return device.slave


def _counter_for(result: object) -> Counter:
    # TES 6.2.3.2: exception replies, "slave not ready" replies, frames executed.
    if isinstance(result, ExceptionCode):
        return Counter.NOT_READY_REPLIES if result is NOT_READY else Counter.EXCEPTION_REPLIES
    return Counter.FRAMES_EXECUTED


@dataclass(order=True, slots=True)
class _Pending:
    at: int
    seq: int
    data: bytes = field(compare=False)
    sender: SlaveDevice | None = field(compare=False)


class Outbox:
    """Replies waiting for their answer delay, sent in (time, order) order."""

    def __init__(self) -> None:
        self._heap: list[_Pending] = []
        self._seq = itertools.count()
        # the same list, for a core that tests emptiness or the next deadline inline
        self.heap: list[_Pending] = self._heap

    def __len__(self) -> int:
        return len(self._heap)

    def put(self, at: int, data: bytes, sender: SlaveDevice | None = None) -> None:
        heapq.heappush(self._heap, _Pending(at, next(self._seq), data, sender))

    def next_deadline(self) -> int | None:
        return self._heap[0].at if self._heap else None

    def due(self, now: int) -> list[tuple[Transmission, SlaveDevice | None]]:
        """Every reply due at or before ``now``, with its sender."""
        out: list[tuple[Transmission, SlaveDevice | None]] = []
        heap = self._heap
        while heap and heap[0].at <= now:
            item = heapq.heappop(heap)
            out.append((Transmission(item.at, item.data), item.sender))
        return out

    def clear(self) -> None:
        self._heap.clear()
