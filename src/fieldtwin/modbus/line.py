"""A multi-drop RTU line: one framer, several slaves (TES 7.1.3, 7.2.6, 6.2.3.2).

Every slave on the line hears every frame.  Line faults (CRC errors, wrong
characters, frames not analysed for lack of silence) and good frames are
counted by all of them, whatever the slave number in the frame: a receiver
checks the CRC before it may trust the slave number.  Only the addressed slave
executes, counts the outcome and replies, after its answer delay; a broadcast
write (slave 0) is executed by all with no reply.  On a single-pair
(two-wire) bus the others also hear that reply and count it as "not analysed"
(TES 6.2.3.2 01Dh: "bus single pair: idem or replies sent by other slaves").

Half-duplex collisions (issue 23 item 3; ``half_duplex``, on for a two-wire RS-485
line): a slave does not listen before it talks, so a master that sends while a
reply is still due (in its answer delay or on the wire) garbles both.  The reply
is lost (the master sees none) and the master's bytes reach no slave as a frame:
one frame with a CRC error for every slave (TES 6.2.3.2 01Ah; docs/manual-notes.md).
``collides(now)`` says it before the bytes are given; ``collide(data, now)`` takes them.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Counter, LineFaultSource, Link, SlaveDevice
from fieldtwin.modbus.pdu import request_length
from fieldtwin.modbus.rtu import Fault, Frame, FramerEvent, RtuFramer
from fieldtwin.modbus.slave import Outbox, SlaveSet, Transmission
from fieldtwin.modbus.timing import RtuTiming, WireTiming

BAD_CRC = "bad_crc"
BROKEN_CHARACTER = "broken_character"


class Wiring(enum.Enum):
    """RS485 bus wiring (TES 6.2.3.2 01Dh)."""

    DOUBLE_PAIR = "double-pair"  # four-wire: slaves never hear each other's replies
    SINGLE_PAIR = "single-pair"  # two-wire: every slave hears the others' replies


class RtuLine:
    """Sans-IO slave side of one RTU line: ``receive``, ``poll``, ``next_deadline``."""

    def __init__(
        self,
        devices: Iterable[SlaveDevice] | SlaveSet,
        link: Link,
        timing: RtuTiming,
        wiring: Wiring = Wiring.DOUBLE_PAIR,
        wire: WireTiming | None = None,
        half_duplex: bool = False,
    ) -> None:
        # one line, one set: the line-wide counters are counted once per frame
        if isinstance(devices, SlaveSet):
            self.slaves = devices
        else:
            self.slaves = SlaveSet(devices, link, shared_counts=True)
        self.link = link
        self.timing = timing
        self.wiring = wiring
        self.wire = wire  # None: a reply leaves its answer delay after the frame
        self.framer = RtuFramer(timing, request_length)
        self._outbox = Outbox()
        self.half_duplex = half_duplex
        self.collisions = 0  # master transmissions that met a reply (half duplex)

    def collides(self, now: int) -> bool:
        """Bytes from the master now would meet a reply still due: a collision."""
        return self.half_duplex and self._outbox.next_deadline() is not None

    def collide(self, data: bytes, now: int) -> None:
        """The master's ``data`` met a reply: both garbled (see the module's docstring)."""
        self.collisions += 1
        self._outbox.clear()  # the reply never reaches the master intact
        self.slaves.count_all(Counter.CRC_ERRORS, now)  # TES 6.2.3.2 01Ah

    def receive(self, data: bytes, now: int) -> None:
        """Bytes that arrived at ``now`` (call ``poll(now)`` next for due replies)."""
        self._handle(self.framer.receive(data, now), now)

    def poll(self, now: int) -> list[Transmission]:
        """Let time reach ``now``: finish frames, return the replies due by then."""
        self._handle(self.framer.poll(now), now)
        out = []
        for transmission, sender in self._outbox.due(now):
            if self.wiring is Wiring.SINGLE_PAIR:
                self._others_hear(sender, transmission.at)
            out.append(transmission)
        return out

    def next_deadline(self) -> int | None:
        """The earliest of the frame-ending silence and the next reply."""
        frame_end, reply = self.framer.next_deadline(), self._outbox.next_deadline()
        if frame_end is None or reply is None:
            return reply if frame_end is None else frame_end
        return min(frame_end, reply)

    def _handle(self, events: list[FramerEvent], now: int) -> None:
        for event in events:
            if isinstance(event, Fault):
                self.slaves.count_all(event.counter, now, event.count)
            else:
                self._frame(event, now)

    def _frame(self, frame: Frame, now: int) -> None:
        if self._injected_fault(frame, now):
            return
        # TES 6.2.3.2 01Ch: "received frames without errors", for every slave.
        self.slaves.count_all(Counter.GOOD_FRAMES, now)
        reply = self.slaves.dispatch(frame.slave, frame.pdu, now)
        if reply is not None:
            data = with_crc(bytes((self.slaves.number_of(reply.device),)) + reply.pdu)
            at = reply.at
            if self.wire is not None:  # a real endpoint: when the line would deliver it
                at = self.wire.reply_at(frame.at, len(frame.data), len(data), reply.at - now)
            self._outbox.put(at, data, reply.device)

    def _injected_fault(self, frame: Frame, now: int) -> bool:
        """A device asked for its next frame to be corrupted on the line."""
        device = self.slaves.get(frame.slave)
        if not isinstance(device, LineFaultSource):
            return False
        fault = device.take_line_fault(self.link)
        if fault is None:
            return False
        if fault.value == BAD_CRC:
            self.slaves.count_all(Counter.CRC_ERRORS, now)  # TES 6.2.3.2 01Ah
        elif fault.value == BROKEN_CHARACTER:
            self.slaves.count_all(Counter.WRONG_CHARACTERS, now)  # TES 6.2.3.2 01Bh
        else:
            raise ConfigError(f"line fault {fault!r}: allowed {BAD_CRC}, {BROKEN_CHARACTER}")
        return True

    def _others_hear(self, sender: SlaveDevice | None, at: int) -> None:
        for device in self.slaves.devices:
            if device is not sender:
                device.count(self.link, Counter.NO_SILENCE, at)
