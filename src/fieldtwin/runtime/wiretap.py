"""What goes over the wire, decoded and published on the plant's event bus.

A ``Wiretap`` belongs to one Modbus server; the server's pump hands its ``Stream``
every chunk that arrived and every transmission it sent, *before* the core sees the
chunk.  On the simulation's thread that is all (``Stream.seen_in``/``seen_out``/
``seen_poll``): one raw record on the bus's buffer - the bytes, the simulated time
and, for a request, the small tuple of each TES's state the request meets (powered,
told not to answer, a line fault pending, its answer delay: ``Wiretap.states``).
Framing, decoding and building the events happen on the observers' side
(``Stream.inbound``/``outbound``/``poll``, fieldtwin.runtime.events), on the
wiretap's own copy of the framing (an MBAP decoder per TCP connection, an RTU
framer with the core's own timing per RTU stream), so it never changes what the
core does.  The pump asks ``bus.watched`` first: an unobserved plant pays one
attribute read per chunk.  A TCP frame that comes whole in its chunk (the usual case)
is decoded once per connection and remembered by its bytes after the transaction
number (and, for a request, the TES states it met; for a reply, its request): the
next such frame gets the same fields and JSON with its own transaction number and
bytes (``Stream.fast``; tests/trace/test_wire_memo.py).  The pure decoding helpers
(a frame's fields, a TES's state and the outcome it gives) are in
fieldtwin.runtime.wirecodec, re-exported here.

``CharTap`` publishes the characters of an SCM channel in and out, one event
per block the line delivered.
"""

from __future__ import annotations

from typing import Any

from fieldtwin.devices.chars import KIND_SERIAL
from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.crc import crc_ok
from fieldtwin.modbus.mbap import MbapDecoder
from fieldtwin.modbus.pdu import EXCEPTION_FLAG, WRITE_FUNCTIONS, request_length
from fieldtwin.modbus.rtu import Fault, Frame, RtuFramer
from fieldtwin.modbus.slave import BROADCAST, SlaveSet
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.runtime.chartap import CharTap
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.obsrecords import (
    OP_EVENT,
    OP_FORGET,
    OP_IN,
    OP_OUT,
    OP_POLL,
    OP_REJECTED,
    template,
)
from fieldtwin.runtime.wirecodec import (
    ANSWERS,
    BROADCAST_EXECUTED,
    BROADCAST_IGNORED,
    FUNCTION_NAMES,
    NOT_ADDRESSED,
    State,
    device_name,
    function_name,
    late_ms,
    mbap_bytes,
    outcome,
    outcome_of,
    reply_fields,
    request_fields,
    request_items,
    state,
    written,
)

KIND_MODBUS = "modbus"
KIND_CONNECTION = "connection"  # a TCP connection opened or closed (the pcap's SYN, FIN, RST)
KIND_REGISTER = "register"
IN, OUT = "in", "out"
MAX_PENDING = 256  # requests remembered per connection to pair their replies
MAX_REJECTED = 256  # bytes of one rejected chunk kept in its event (one RTU frame's worth)
MEMO = 256  # TCP frames remembered per connection (``Stream.fast``), forgotten all at once
# a remembered frame: (device, fields with a placeholder transaction and hex, the JSON
# body's head and tail around them or None, a request's (address, count, write))
Remembered = tuple[str, dict[str, object], tuple[str, str] | None, Any]


class Stream:
    """The tap on one transport (a TCP connection or an RTU line).

    ``fast``: a TCP frame that comes whole in its chunk, the usual case, is published
    from what the stream remembers of the same frame (its fields but the transaction
    number and bytes, and its JSON around them: ``_memo``); False: every frame goes
    through the framing and decoding (the reference, tests/trace/test_wire_memo.py)."""

    fast = True

    def __init__(self, tap: Wiretap, conn: str, number: int | None = None) -> None:
        self.tap = tap
        self.conn = conn
        self._mbap = MbapDecoder()
        self._framer = RtuFramer(tap.timing, request_length) if tap.timing is not None else None
        # transaction or slave -> (address, count, the PDU of a write) of its request
        self._pending: dict[int, tuple[object, object, bytes | None]] = {}
        self.rtu = self._framer is not None
        self._states: tuple[State, ...] | None = None  # what the record being decoded met
        # (decoding, the bytes after the transaction number, what it met) of a request,
        # (decoding, unit, function, exception or byte count, its request) of a reply ->
        # what every such frame gives: a master polls the same requests
        self._memo: dict[tuple[Any, ...], Remembered] = {}
        self.sid = tap.bus.attach(self, number)  # the number its records name it by

    # -- the pump's calls (the simulation's thread): one raw record each -------------

    def seen_in(self, data: bytes, now: int) -> None:
        """A chunk arrived (before the core sees it: the TES states it meets are now's)."""
        self.tap.bus.post((OP_IN, self.sid, bytes(data), now, self.tap.states(self.rtu)))

    def seen_poll(self, now: int) -> None:
        """The core was polled (an RTU line: a frame may end by silence now)."""
        if self.rtu:
            self.tap.bus.post((OP_POLL, self.sid, now, self.tap.states(True)))

    def seen_out(self, data: bytes, now: int) -> None:
        self.tap.bus.post((OP_OUT, self.sid, bytes(data), now))

    def seen_connection(self, now: int, state: str, by: str) -> None:
        """A TCP connection opened (``open``) or closed (``fin``, ``rst``) by ``by``
        (``master`` or ``twin``): a ``connection`` event, not in the JSON trace."""
        tap = self.tap
        data = {
            "endpoint": tap.endpoint,
            "transport": tap.transport,
            "listen": tap.where,
            "conn": self.conn,
            "state": state,
            "by": by,
        }
        tap.bus.post((OP_EVENT, now, KIND_CONNECTION, tap.endpoint, data))
        if state != "open":  # the connection's stream is done with
            tap.bus.control((OP_FORGET, self.sid))

    def seen_rejected(
        self, data: bytes, now: int, reason: str, note: str, fault: str = "wrong_characters"
    ) -> None:
        """Bytes the line rejected before any framing (runtime/uart.py, a collision)."""
        self.tap.bus.post((OP_REJECTED, self.sid, bytes(data), now, reason, note, fault))

    # -- the observers' side: framing, decoding, events --------------------------------

    def rejected(
        self, data: bytes, now: int, reason: str, note: str, fault: str = "wrong_characters"
    ) -> None:
        fields: dict[str, object] = {
            "crc": "bad" if fault == "crc_errors" else None,
            "fault": fault,
            "fault_count": 1 if fault == "crc_errors" else len(data),
            "reason": reason,
            "hex": data[:MAX_REJECTED].hex(),
            "note": note,
        }
        self._publish(now, IN, None, fields)

    def inbound(self, data: bytes, now: int, states: tuple[State, ...] | None = None) -> None:
        self._states = states
        if self._framer is None:
            self._tcp_in(data, now)
        else:
            self._rtu_events(self._framer.receive(data, now), now)

    def poll(self, now: int, states: tuple[State, ...] | None = None) -> None:
        if self._framer is not None:
            self._states = states
            self._rtu_events(self._framer.poll(now), now)

    def outbound(self, data: bytes, now: int) -> None:
        if self._framer is None:
            self._tcp_out(data, now)
        else:
            self._rtu_out(data, now)

    # -- Modbus TCP ------------------------------------------------------------------

    def _tcp_in(self, data: bytes, now: int) -> None:
        size = len(data)
        if (
            self.fast
            and 8 <= size <= 260
            and not self._mbap.partial
            and (data[4] << 8 | data[5]) == size - 6
        ):  # one whole frame, nothing held back: as MbapDecoder.feed would cut it
            decode = self.tap.bus.decoding
            key = (decode, data[6:], self._states)
            known = self._memo.get(key)
            if known is None:
                known = self._learn_in(key, data)
            transaction = (data[0] << 8) | data[1]
            if known[3] is not None:
                self._pending_put(transaction, known[3])
            self._known(now, transaction, data, known)
            return
        try:
            frames = self._mbap.feed(data)
        except ProtocolError as exc:
            self._mbap = MbapDecoder()
            self._publish(now, IN, None, {"error": str(exc), "hex": data[:260].hex()})
            return
        whole = len(frames) == 1 and len(data) == 7 + len(frames[0].pdu)  # the usual chunk
        decode = self.tap.bus.decoding
        for frame in frames:
            raw = (
                data
                if whole
                else mbap_bytes(frame.transaction, frame.protocol, frame.unit, frame.pdu)
            )
            fields: dict[str, object] = {"transaction": frame.transaction, "hex": raw.hex()}
            if decode:
                fields.update(request_items(frame.pdu))
                fields["tes"] = self.tap.outcomes(frame.unit, frame.pdu, False, self._states)
                self._remember(frame.transaction, frame.unit, fields, frame.pdu)
            self._publish(now, IN, frame.unit, fields)

    def _tcp_out(self, data: bytes, now: int) -> None:
        if len(data) < 8:
            return
        if self.fast:
            transaction = (data[0] << 8) | data[1]
            decode = self.tap.bus.decoding
            request = self._pending.pop(transaction, None) if decode else None
            key = (decode, data[6:9], request)
            known = self._memo.get(key)
            if known is None:
                known = self._learn_out(key, data, request)
            self._known(now, transaction, data, known)
            if request is not None and request[2] is not None:
                self._register(now, data[6], request[2], data[7:])
            return
        transaction, unit, pdu = (data[0] << 8) | data[1], data[6], data[7:]
        fields: dict[str, object] = {"transaction": transaction, "hex": data.hex()}
        if not self.tap.bus.decoding:  # only the bytes are wanted (a pcap)
            self._publish(now, OUT, unit, fields)
            return
        write = self._pending.get(transaction, _NOTHING)[2]
        fields.update(self._reply(transaction, unit, pdu))
        self._publish(now, OUT, unit, fields)
        self._register(now, unit, write, pdu)

    # -- Modbus RTU ------------------------------------------------------------------

    def _rtu_events(self, events: list[Frame | Fault], now: int) -> None:
        for event in events:
            if isinstance(event, Fault):
                fields: dict[str, object] = {
                    "crc": "bad" if event.counter.value == "crc_errors" else None,
                    "fault": event.counter.value,
                    "fault_count": event.count,
                }
                if event.reason:  # issue 23: why, and the bytes themselves
                    fields["reason"] = event.reason
                    fields["hex"] = event.data.hex()
                self._publish(event.at, IN, None, fields)
                continue
            slave, pdu = event.slave, event.pdu
            fields = {"crc": "good", "hex": event.data.hex()}
            if not self.tap.bus.decoding:  # only the bytes are wanted (a pcap)
                self._publish(event.at, IN, slave, fields)
                continue
            fields.update(request_items(pdu))
            fields["tes"] = self.tap.outcomes(slave, pdu, True, self._states)
            self._remember(slave, slave, fields, pdu)
            self._publish(event.at, IN, slave, fields)
            if slave == BROADCAST:  # executed by every TES that heard it, never answered
                self._broadcast(event.at, pdu, fields)

    def _rtu_out(self, data: bytes, now: int) -> None:
        if len(data) < 4:
            return
        slave = data[0]
        fields: dict[str, object] = {"crc": "good" if crc_ok(data) else "bad", "hex": data.hex()}
        if not self.tap.bus.decoding:  # only the bytes are wanted (a pcap)
            self._publish(now, OUT, slave, fields)
            return
        write = self._pending.get(slave, _NOTHING)[2]
        fields.update(self._reply(slave, slave, data[1:-2]))
        self._publish(now, OUT, slave, fields)
        self._register(now, slave, write, data[1:-2])

    # -- both ------------------------------------------------------------------------

    def _remember(self, key: int, unit: int, fields: dict[str, object], pdu: bytes) -> None:
        self._pending_put(key, _request_of(fields, pdu))

    def _pending_put(self, key: int, request: tuple[object, object, bytes | None]) -> None:
        pending = self._pending
        if len(pending) >= MAX_PENDING:
            pending.pop(next(iter(pending)))
        pending[key] = request

    # -- remembered TCP frames (``fast``) --------------------------------------------

    def _known(self, now: int, transaction: int, data: bytes, known: Remembered) -> None:
        """Publish a frame from what is remembered of it: its fields and JSON but its
        transaction number and bytes."""
        device, fields, around, _ = known
        hexed = data.hex()
        fields = fields.copy()  # the keys in their order: the placeholders replaced
        fields["transaction"] = transaction
        fields["hex"] = hexed
        body = (
            None
            if around is None
            else around[0] + str(transaction) + ',"hex":"' + hexed + around[1]
        )
        self.tap.bus.deliver(now, KIND_MODBUS, device, fields, body)

    def _learn_in(self, key: tuple[Any, ...], data: bytes) -> Remembered:
        """What every request of these bytes (but the transaction number) gives, by the
        general decoding (``_tcp_in``'s)."""
        unit, pdu = data[6], data[7:]
        fields: dict[str, object] = {"transaction": 0, "hex": ""}
        request = None
        if key[0]:
            fields.update(request_items(pdu))
            fields["tes"] = self.tap.outcomes(unit, pdu, False, self._states)
            request = _request_of(fields, pdu)
        return self._learnt(key, unit, IN, fields, request)

    def _learn_out(
        self, key: tuple[Any, ...], data: bytes, request: tuple[object, object, bytes | None] | None
    ) -> Remembered:
        """What every reply of this unit, function and exception to this request gives
        (``_tcp_out``'s decoding; the reply's fields read only those: ``reply_fields``)."""
        unit = data[6]
        fields: dict[str, object] = {"transaction": 0, "hex": ""}
        if key[0]:
            fields.update(self._replied(unit, data[7:], request))
        return self._learnt(key, unit, OUT, fields, None)

    def _learnt(
        self,
        key: tuple[Any, ...],
        unit: int,
        direction: str,
        fields: dict[str, object],
        request: tuple[object, object, bytes | None] | None,
    ) -> Remembered:
        device, data = self.tap.frame(direction, unit, self.conn, fields)
        known = (device, data, template(KIND_MODBUS, device, data, "transaction"), request)
        memo = self._memo
        if len(memo) >= MEMO:
            memo.clear()
        memo[key] = known
        return known

    def _register(self, now: int, unit: int, request: object, reply: bytes) -> None:
        """A write the TES answered without an exception: a ``register`` event."""
        if not isinstance(request, bytes) or not reply or reply[0] & EXCEPTION_FLAG:
            return
        name = self.tap.names.get(unit)
        if name is not None:
            self._wrote(now, unit, name, request)

    def _broadcast(self, now: int, pdu: bytes, fields: dict[str, object]) -> None:
        outcomes = fields.get("tes")
        if not isinstance(outcomes, dict):
            return
        for number, name in self.tap.roster:
            if outcomes.get(name) == BROADCAST_EXECUTED:
                self._wrote(now, number, name, pdu)

    def _wrote(self, now: int, unit: int, name: str, pdu: bytes) -> None:
        what = written(pdu)
        if what is None:
            return
        table, address, values = what
        data: dict[str, object] = {
            "endpoint": self.tap.endpoint,
            "conn": self.conn,
            "slave": unit,
            "tes": name,
            "function": pdu[0],
            "table": table,
            "address": address,
            "values": values,
        }
        self.tap.bus.deliver(now, KIND_REGISTER, f"{self.tap.endpoint} {unit}", data)

    def _reply(self, key: int, unit: int, pdu: bytes) -> dict[str, object]:
        return self._replied(unit, pdu, self._pending.pop(key, None))

    def _replied(
        self, unit: int, pdu: bytes, request: tuple[object, object, bytes | None] | None
    ) -> dict[str, object]:
        """A reply's fields: its own, its request's address and count, who answered."""
        fields = reply_fields(pdu)
        if request is not None:
            address, count, _ = request
            if address is not None:
                fields["address"] = address
            if count is not None:
                fields["count"] = count
        fields["from"] = self.tap.names.get(unit, "server")
        return fields

    def _publish(
        self, t_us: int, direction: str, slave: int | None, fields: dict[str, object]
    ) -> None:
        self.tap.publish(t_us, direction, slave, self.conn, fields)


_NOTHING: tuple[object, object, bytes | None] = (None, None, None)


def _request_of(fields: dict[str, object], pdu: bytes) -> tuple[object, object, bytes | None]:
    """What a reply's decoding needs of its request: address, count, the PDU of a write."""
    write = pdu if pdu and pdu[0] in WRITE_FUNCTIONS else None
    return (fields.get("address"), fields.get("count"), write)


class Wiretap:
    """Decodes and publishes the frames of one Modbus server.

    On the simulation's side it holds the ``slaves`` (whose states a request meets);
    the decoding needs only their numbers and names (``roster``): a wiretap is rebuilt
    from ``spec()`` in the observers' process (fieldtwin.runtime.obsproc)."""

    def __init__(
        self,
        bus: EventBus,
        endpoint: str,
        transport: str,
        slaves: SlaveSet | None,
        timing: RtuTiming | None,
        where: str = "",
        roster: tuple[tuple[int, str], ...] | None = None,
    ) -> None:
        self.bus = bus
        self.endpoint = endpoint  # as the plant file names it
        self.where = where  # where it listens (the port a port 0 got), or the pty
        self.transport = transport  # "tcp", "rtu+tcp", "rtu"
        self.slaves = slaves
        self.timing = timing  # None: MBAP framing
        if roster is None:
            assert slaves is not None
            roster = tuple((slaves.number_of(d), device_name(d)) for d in slaves.devices)
        self.roster = roster  # (slave number, TES name) in ``slaves.devices`` order
        self.names = dict(roster)
        self.tid = bus.new_id()
        self._outcomes: dict[tuple[object, ...], dict[str, str]] = {}  # remembered, bounded

    def spec(self) -> tuple[Any, ...]:
        """What the observers' process rebuilds this wiretap from (plain data)."""
        return (self.endpoint, self.transport, self.roster, self.timing, self.where)

    @classmethod
    def from_spec(cls, bus: EventBus, spec: tuple[Any, ...]) -> Wiretap:
        endpoint, transport, roster, timing, where = spec
        return cls(bus, endpoint, transport, None, timing, where, roster=tuple(roster))

    def stream(self, conn: str, number: int | None = None) -> Stream:
        return Stream(self, conn, number)

    def states(self, rtu: bool) -> tuple[State, ...]:
        """Each TES's state now, in ``slaves.devices`` order (the simulation's thread)."""
        slaves = self.slaves
        assert slaves is not None  # the simulation's side
        return tuple(state(device, slaves.link, rtu) for device in slaves.devices)

    def outcomes(
        self, unit: int, pdu: bytes, rtu: bool, states: tuple[State, ...] | None = None
    ) -> dict[str, str]:
        """What each TES behind this server does with the request, by TES name, from
        ``states`` (what the request met; read now when not given)."""
        if states is None:
            states = self.states(rtu)
        writes = bool(pdu) and pdu[0] in WRITE_FUNCTIONS
        key = (unit, writes, rtu, states)
        known = self._outcomes.get(key)
        if known is not None:
            return dict(known)
        out = self._outcomes_of(unit, writes, rtu, states)
        if len(self._outcomes) >= MAX_PENDING:
            self._outcomes.clear()
        self._outcomes[key] = out
        return dict(out)

    def _outcomes_of(
        self, unit: int, writes: bool, rtu: bool, states: tuple[State, ...]
    ) -> dict[str, str]:
        out: dict[str, str] = {}
        single = len(self.roster) == 1
        for (number, name), meets in zip(self.roster, states, strict=True):
            if unit == BROADCAST:
                result = outcome_of(meets)
                if result == ANSWERS:
                    result = BROADCAST_EXECUTED if writes else BROADCAST_IGNORED
                out[name] = result
            elif number == unit or (not rtu and unit == 0xFF and single):
                result = outcome_of(meets)
                if result == ANSWERS and meets is not None and meets[3]:
                    result = f"{ANSWERS} after {late_ms(meets):g} ms"
                out[name] = result
            else:
                out[name] = NOT_ADDRESSED
        return out

    def publish(
        self, t_us: int, direction: str, slave: int | None, conn: str, fields: dict[str, object]
    ) -> None:
        device, data = self.frame(direction, slave, conn, fields)
        self.bus.deliver(t_us, KIND_MODBUS, device, data)

    def frame(
        self, direction: str, slave: int | None, conn: str, fields: dict[str, object]
    ) -> tuple[str, dict[str, object]]:
        """The device and the data of a ``modbus`` event."""
        data: dict[str, object] = {
            "endpoint": self.endpoint,
            "transport": self.transport,
            "listen": self.where,
            "conn": conn,
            "dir": direction,
            "slave": slave,
            **fields,
        }
        known = slave is not None and slave in self.names
        return (f"{self.endpoint} {slave}" if known else self.endpoint), data


__all__ = [
    "ANSWERS",
    "FUNCTION_NAMES",
    "KIND_MODBUS",
    "KIND_SERIAL",
    "NOT_ADDRESSED",
    "CharTap",
    "Stream",
    "Wiretap",
    "function_name",
    "outcome",
    "outcome_of",
    "reply_fields",
    "request_fields",
    "state",
]
