"""Issue 25 item 2: a TCP session's fused path answers what the general path answers.

Two sessions, one fused (the default) and one with ``fused = False`` (every frame
through ``MbapDecoder``, ``SlaveSet.answer`` and the general encoders: the
reference), each with its own devices, get the same byte stream cut into the
same random chunks: requests valid and not (every function code, bad quantities,
byte counts and lengths, unknown functions, other units, broadcasts, another
protocol id, a length that cannot be resynchronised), pipelined or split anywhere.
After every chunk both sent the same bytes at the same instants, the devices saw
the same calls in the same order and counted the same, and the TES's memory is
the same; a device's bad result raises the same error on both.
"""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import SimClock
from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import Link, ReadWords, Request, Result
from fieldtwin.modbus.session import TcpSession
from fieldtwin.tes import Tes
from tests.modbus.modbus_fakes import TableDevice

_FUNCTIONS = (1, 2, 3, 4, 5, 6, 7, 0x0F, 0x10, 0x08, 0x11, 0x2B, 0x83)


@st.composite
def _pdu(draw: st.DrawFn) -> bytes:
    """A request PDU, mostly well formed, often not."""
    fc = draw(st.sampled_from(_FUNCTIONS))
    address = draw(st.one_of(st.integers(0, 80), st.integers(0, 0xFFFF)))
    count = draw(st.one_of(st.integers(1, 12), st.integers(0, 2010)))
    head = bytes((fc,)) + address.to_bytes(2, "big")
    kind = draw(st.integers(0, 9))
    if kind == 0:  # anything at all
        return draw(st.binary(min_size=1, max_size=20))
    if fc in (0x0F, 0x10):
        values = draw(st.binary(max_size=30)) if kind == 1 else None
        if values is None:
            size = 2 * count if fc == 0x10 else (count + 7) // 8
            values = draw(st.binary(min_size=min(size, 40), max_size=min(size, 40)))
        tail = count.to_bytes(2, "big")
        byte_count = len(values) if kind != 2 else draw(st.integers(0, 255))
        return head + tail + bytes((byte_count & 0xFF,)) + values
    if fc == 5:
        value = draw(st.sampled_from((0xFF00, 0x0000, 0x1234)))
        return head + value.to_bytes(2, "big")
    if fc == 7 and kind < 8:
        return bytes((7,))
    if kind == 3:
        return head + count.to_bytes(2, "big") + b"\x00"  # one byte too many
    return head + count.to_bytes(2, "big")


@st.composite
def _frame(draw: st.DrawFn) -> bytes:
    pdu = draw(_pdu())
    tid = draw(st.integers(0, 0xFFFF))
    unit = draw(st.sampled_from((1, 1, 1, 1, 0xFF, 0, 2, 9)))
    protocol = draw(st.sampled_from((0, 0, 0, 0, 0, 1)))
    if draw(st.integers(0, 40)) == 0:  # a length that cannot be resynchronised
        return struct.pack(">HHHB", tid, protocol, draw(st.sampled_from((0, 1, 255, 300))), unit)
    return struct.pack(">HHHB", tid, protocol, len(pdu) + 1, unit) + pdu


@st.composite
def _chunks(draw: st.DrawFn) -> list[bytes]:
    stream = b"".join(draw(st.lists(_frame(), min_size=1, max_size=12)))
    cuts = sorted(draw(st.lists(st.integers(0, len(stream)), max_size=4)))
    if draw(st.booleans()):
        cuts = []  # whole frames, the usual case
    pieces, last = [], 0
    for cut in [*cuts, len(stream)]:
        if cut > last:
            pieces.append(stream[last:cut])
            last = cut
    return pieces


def _run(session: TcpSession, chunks: list[bytes], step: int) -> list[object]:
    """What a session sends, chunk by chunk (or the error it raises)."""
    out: list[object] = []
    now = 0
    for chunk in chunks:
        now += step
        try:
            session.receive(chunk, now)
        except ProtocolError as exc:
            out.append(("error", str(exc)))
        for later in (now, now + 3_000, now + 50_000):
            out.append([(t.at, t.data) for t in session.poll(later)])
        out.append((session.closed, session.close_reason, session.next_deadline()))
    return out


@settings(max_examples=300, deadline=None)
@given(_chunks(), st.sampled_from((0, 2_000)), st.booleans())
def test_fused_and_general_table_devices(chunks: list[bytes], delay: int, two: bool) -> None:
    runs = []
    for fused in (True, False):
        devices = [TableDevice(1, delay_us=delay)] + ([TableDevice(2)] if two else [])
        session = TcpSession(devices)
        session.fused = fused
        runs.append((_run(session, chunks, 1_000), [(d.log, d.counters, d.words) for d in devices]))
    assert runs[0] == runs[1]


def _tes_state(tes: Tes) -> object:
    ram = tes.ram
    counters = {key: list(c.values) for key, c in ram.counters.items()}
    words = [tes.peek_word(a) for a in sorted(tes.registers.table)]
    return counters, dict(ram.words), ram.status, words, tes.clock.pending


@settings(max_examples=200, deadline=None)
@given(
    _chunks(),
    st.sampled_from(("32EST", "16EST", "8EA", "32ET")),
    st.sampled_from((None, "late", "not_ready", "off", "no_answer")),
)
def test_fused_and_general_tes(chunks: list[bytes], model: str, fault: str | None) -> None:
    runs = []
    for fused in (True, False):
        clock = SimClock()
        tes = Tes(model, 1, clock=clock)
        tes.set_input(0, True) if model != "8EA" else None
        if fault == "late":
            tes.set_late_answer(2)
        elif fault == "not_ready":
            tes.set_not_ready(True)
        elif fault == "off":
            tes.power_off()
        elif fault == "no_answer":
            tes.set_no_answer(True)
        session = TcpSession([tes], Link.TCP)
        session.fused = fused
        sent = _run(session, chunks, 7_000)
        runs.append((sent, _tes_state(tes)))
    assert runs[0] == runs[1]


class _BadWords(TableDevice):
    """Answers a read with what is not a 16-bit word, or with the wrong count."""

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        if isinstance(request, ReadWords) and request.address == 7:
            return (0x10000,) * request.count
        if isinstance(request, ReadWords) and request.address == 8:
            return (1,)
        if isinstance(request, ReadWords) and request.address == 9:
            return (True,) * request.count
        return super().execute(request, link, now, broadcast)


@pytest.mark.parametrize("address", [7, 8, 9])
def test_a_bad_device_result_gives_the_same_error_or_bytes(address: int) -> None:
    frame = encode_mbap(5, 1, bytes((3,)) + address.to_bytes(2, "big") + (2).to_bytes(2, "big"))
    runs = []
    for fused in (True, False):
        session = TcpSession([_BadWords(1)])
        session.fused = fused
        runs.append(_run(session, [frame], 1))
    assert runs[0] == runs[1]
