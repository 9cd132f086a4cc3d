"""Issue 10 item 5: the RTU frame buffer is bounded and a burst is a UART overrun."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Counter, ReadWords, WriteWords
from fieldtwin.modbus.pdu import encode_request, request_length
from fieldtwin.modbus.rtu import MAX_FRAME, Fault, Frame, FramerEvent, RtuFramer, State
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.transports.base import line_settings

SIM = RtuTiming.from_format(line_settings(9600, 8, "E", 1))
CT = SIM.char_us
LEAD = MAX_FRAME * CT
REAL = SIM.relaxed(2000, eager=True, max_lead_us=LEAD)
READ = with_crc(b"\x01" + encode_request(ReadWords(3, 0, 2)))
FAR = 10**12


def faults(events: list[FramerEvent]) -> dict[Counter, int]:
    out: dict[Counter, int] = {}
    for e in events:
        if isinstance(e, Fault):
            out[e.counter] = out.get(e.counter, 0) + e.count
    return out


def frames(events: list[FramerEvent]) -> list[bytes]:
    return [e.data for e in events if isinstance(e, Frame)]


def test_a_frame_longer_than_256_bytes_is_one_crc_error_and_is_never_held() -> None:
    f = RtuFramer(SIM, request_length)
    events = []
    for i in range(40):  # 40 x 10 garbage bytes, back to back
        events += f.receive(b"\x07" * 10, i * 10 * CT)
        assert len(f._buf) <= MAX_FRAME
    assert f.state is State.OVERLONG
    events += f.poll(FAR)
    assert faults(events) == {Counter.CRC_ERRORS: 1} and frames(events) == []
    # TES 7.1.3: after the t3.5 silence the next frame is heard again
    assert frames(f.receive(READ, FAR) + f.poll(2 * FAR)) == [READ]


def test_a_263_byte_frame_with_a_valid_crc_is_not_a_frame() -> None:
    # fc16, 127 words, byte count 254: its own length says 263 bytes, past MAX_FRAME
    body = b"\x01\x10\x00\x00\x00\x7f\xfe" + bytes(254)
    for timing in (SIM, REAL):
        f = RtuFramer(timing, request_length)
        events = f.receive(with_crc(body), 10**9) + f.poll(FAR)
        assert frames(events) == [] and faults(events) == {Counter.CRC_ERRORS: 1}


def test_back_to_back_frames_past_256_bytes_are_never_dropped() -> None:
    write = with_crc(b"\x02" + encode_request(WriteWords(0, tuple(range(100)))))  # 209 bytes
    stream = write + READ + write + READ
    f = RtuFramer(SIM, request_length)
    events = f.receive(stream, 0) + f.poll(FAR)
    assert frames(events) == [write, READ, write, READ] and faults(events) == {}


def test_a_burst_on_a_real_line_is_an_overrun_and_the_line_hears_again_after_t35() -> None:
    f = RtuFramer(REAL, request_length)
    now, events = 10**9, []
    for _ in range(1000):  # 4 MB: 1000 reads of 4 KiB at pty speed, 1 ms apart
        events += f.receive(b"\xff" * 4096, now)
        assert len(f._buf) <= MAX_FRAME
        now += 1000
    burst_end = now
    lost = faults(events + f.poll(burst_end))[Counter.WRONG_CHARACTERS]
    carried = 1000 * 4096 - lost
    assert carried <= (burst_end - 10**9 + LEAD) // CT + 4096  # never faster than the baud rate
    # free again at most one longest frame + t3.5 after the burst
    ready = burst_end + LEAD + REAL.t35_us
    events = f.poll(ready)
    assert f.state is State.IDLE
    got = f.receive(READ, ready + 20_000) + f.poll(ready + 20_000 + 10 * CT)
    assert frames(got) == [READ]


def test_a_frame_written_at_once_on_a_real_line_arrives_when_it_is_read() -> None:
    f = RtuFramer(REAL, request_length)
    now = 5_000_000
    assert f.receive(READ, now) == [Frame(READ, now)]  # back-dated: its bytes were on the wire


@given(
    st.lists(st.tuples(st.integers(0, 50_000), st.binary(min_size=1, max_size=5000)), max_size=30)
)
def test_a_real_line_never_holds_more_than_a_frame(steps: list[tuple[int, bytes]]) -> None:
    f = RtuFramer(REAL, request_length)
    now = 10**9
    for gap, data in steps:
        now += gap
        f.receive(data, now)
        assert len(f._buf) <= MAX_FRAME
        assert f.next_deadline() is None or f.next_deadline() <= now + LEAD + REAL.t35_us
