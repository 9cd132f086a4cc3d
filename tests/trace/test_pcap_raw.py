"""A pcap alone does not make the wiretaps decode the frames' fields, and writes the
same file as when another observer has them decoded (fieldtwin.runtime.events,
``raw`` subscriptions; docs/decisions.md, "Observers: what each one needs")."""

from __future__ import annotations

import os
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.pcap import PcapWriter
from fieldtwin.runtime.wiretap import Wiretap

EXAMPLES = 10 if os.environ.get("FIELDTWIN_FAST_EXAMPLES") else 60
ROSTER = ((1, "TES #1"), (2, "TES #2"))
TIMING = RtuTiming(char_us=573, t15_us=860, t35_us=2005)

# requests and replies as a master and two TES exchange them (the PDUs)
PDUS = [
    bytes.fromhex("0300250010"),  # read 16 words at 37
    bytes.fromhex("03200102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f20"),
    bytes.fromhex("060005abcd"),  # write one word
    bytes.fromhex("10002500020400010002"),  # write two words
    bytes.fromhex("1000250002"),
    bytes.fromhex("8302"),  # an exception
    bytes.fromhex("16"),  # a function the TES does not know
]


def _mbap(transaction: int, unit: int, pdu: bytes) -> bytes:
    return (
        transaction.to_bytes(2, "big")
        + b"\x00\x00"
        + (len(pdu) + 1).to_bytes(2, "big")
        + bytes((unit,))
        + pdu
    )


steps = st.lists(
    st.tuples(
        st.sampled_from(["in", "out"]),
        st.integers(0, 0xFFFF),  # transaction
        st.sampled_from([1, 2, 0, 7]),  # unit / slave
        st.sampled_from(PDUS),
        st.integers(0, 3),  # how the chunk is cut: whole, split, two frames, garbage
        st.integers(1, 5_000),  # microseconds since the step before
    ),
    max_size=40,
)


def _drive(bus: EventBus, steps: list[tuple[str, int, int, bytes, int, int]]) -> None:
    tcp = Wiretap(bus, "tcp://127.0.0.1:5020", "tcp", None, None, "tcp://127.0.0.1:5020", ROSTER)
    rtu = Wiretap(bus, "rtu:///dev/pts/9", "rtu", None, TIMING, "/dev/pts/9", ROSTER)
    conn, line = tcp.stream("127.0.0.1:40000"), rtu.stream("/dev/pts/9")
    now = 0
    for direction, transaction, unit, pdu, cut, gap in steps:
        now += gap
        framed = _mbap(transaction, unit, pdu)
        serial = with_crc(bytes((unit,)) + pdu)
        if cut == 1:
            chunks = [framed[:5], framed[5:]]
            serial_chunks = [serial[:2], serial[2:]]
        elif cut == 2:
            chunks = [framed + _mbap((transaction + 1) & 0xFFFF, unit, pdu)]
            serial_chunks = [serial]
        elif cut == 3:
            chunks = [b"\x00\x01\x00\x07" + framed[:3]]  # a bad protocol id: an error event
            serial_chunks = [b"\xff" + serial[1:]]  # a bad CRC
        else:
            chunks, serial_chunks = [framed], [serial]
        for chunk in chunks:
            if direction == "in":
                conn.inbound(chunk, now, (None, None))
            else:
                conn.outbound(chunk, now)
        for chunk in serial_chunks:
            if direction == "in":
                line.inbound(chunk, now, (None, None))
            else:
                line.outbound(chunk, now)
        now += 3_000
        line.poll(now, (None, None))  # the silence ends an RTU frame


def _pcap(tmp: Path, name: str, steps: list, decoded: bool) -> tuple[bytes, bool, int]:
    bus = EventBus()
    path = tmp / f"{name}.pcap"
    writer = PcapWriter(bus, path, start_wall=1_700_000_000.0, rtu_lines=True)
    other = bus.subscribe(["modbus"]) if decoded else None
    decoding = bus.decoding
    _drive(bus, steps)
    writer.close()
    fields = 0
    if other is not None:  # the decoded events have their fields
        fields = sum(1 for e in other.take(100_000) if "function" in e.data)
    return path.read_bytes(), decoding, fields


@settings(max_examples=EXAMPLES, deadline=None)
@given(steps=steps)
def test_a_pcap_alone_writes_what_it_writes_beside_a_decoding_observer(
    tmp_path_factory, steps: list
) -> None:
    tmp = tmp_path_factory.mktemp("pcap")
    alone, alone_decoding, _ = _pcap(tmp, "alone", steps, decoded=False)
    beside, beside_decoding, _ = _pcap(tmp, "beside", steps, decoded=True)
    assert not alone_decoding and beside_decoding
    assert alone == beside


def test_the_bus_decodes_while_a_subscription_other_than_a_raw_one_wants_modbus(
    tmp_path: Path,
) -> None:
    bus = EventBus()
    writer = PcapWriter(bus, tmp_path / "x.pcap", start_wall=0.0)
    assert not bus.decoding  # a pcap reads bytes only
    leds = bus.subscribe(["led"])
    assert not bus.decoding  # nor does a subscriber of LEDs need frames decoded
    every = bus.subscribe()  # every kind: modbus too
    assert bus.decoding
    every.close()
    assert not bus.decoding
    registers = bus.subscribe(["register"])  # a write's registers come from the decoding
    assert bus.decoding
    registers.close()
    leds.close()
    writer.close()
    assert not bus.decoding


def test_the_fields_are_decoded_for_the_other_observer() -> None:
    steps = [("in", 5, 1, PDUS[0], 0, 10), ("out", 5, 1, PDUS[1], 0, 10)]
    bus = EventBus()
    sub = bus.subscribe(["modbus"])
    _drive(bus, steps)
    events = sub.take()
    assert events and all(
        "function" in e.data for e in events if "crc" not in e.data or e.data["crc"] == "good"
    )
