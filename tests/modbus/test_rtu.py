"""The RTU framer: silences, back-to-back frames, CRC errors, short and broken frames."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.modbus.crc import crc_ok, with_crc
from fieldtwin.modbus.model import Counter, ReadWords, Request
from fieldtwin.modbus.pdu import encode_request, request_length
from fieldtwin.modbus.rtu import Fault, Frame, FramerEvent, RtuFramer, State
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.transports.base import line_settings
from tests.modbus.modbus_strategies import small_requests

LINE = line_settings(9600, 8, "E", 1)
TIMING = RtuTiming.from_format(LINE)  # char 1146 us, t1.5 1719 us, t3.5 4010 us
CT, T15, T35 = TIMING.char_us, TIMING.t15_us, TIMING.t35_us
FAR = 10**9


def rtu(slave: int, request: Request) -> bytes:
    return with_crc(bytes((slave,)) + encode_request(request))


READ = rtu(1, ReadWords(3, 0, 2))

frames_st = st.builds(rtu, st.integers(0, 247), small_requests)


def framer(timing: RtuTiming = TIMING) -> RtuFramer:
    return RtuFramer(timing, request_length)


def run(f: RtuFramer, chunks: list[tuple[int, bytes]]) -> list[FramerEvent]:
    events: list[FramerEvent] = []
    for at, data in chunks:
        events += f.poll(at)
        events += f.receive(data, at)
    return events + f.poll(FAR)


def faults(events: list[FramerEvent]) -> list[tuple[Counter, int]]:
    return [(e.counter, e.count) for e in events if isinstance(e, Fault)]


def frames(events: list[FramerEvent]) -> list[bytes]:
    return [e.data for e in events if isinstance(e, Frame)]


def state_of(f: RtuFramer) -> State:
    return f.state


def test_a_frame_ends_after_t35_of_silence() -> None:
    f = framer()
    assert f.receive(READ, 1000) == []
    end = 1000 + len(READ) * CT  # bytes spread at one character time each
    assert f.next_deadline() == end + T35
    assert f.poll(end + T35 - 1) == []
    assert f.poll(end + T35) == [Frame(READ, end + T35)]
    assert f.state is State.IDLE and f.next_deadline() is None


def test_bytes_one_by_one_within_t15_make_one_frame() -> None:
    chunks = [(i * (CT + T15), READ[i : i + 1]) for i in range(len(READ))]
    assert run(framer(), chunks) == [Frame(READ, 7 * (CT + T15) + CT + T35)]


@given(st.lists(st.tuples(frames_st, st.integers(0, 50_000)), min_size=1, max_size=6))
def test_frames_separated_by_t35_are_delivered_in_order(items: list[tuple[bytes, int]]) -> None:
    chunks, at = [], 0
    for data, extra in items:
        chunks.append((at, data))
        at += len(data) * CT + T35 + extra
    events = run(framer(), chunks)
    assert frames(events) == [data for data, _ in items] and faults(events) == []


@given(st.lists(frames_st, min_size=2, max_size=6))
def test_back_to_back_frames_in_one_read_are_never_dropped(items: list[bytes]) -> None:
    events = run(framer(), [(0, b"".join(items))])
    assert frames(events) == items and faults(events) == []


@given(st.lists(frames_st, min_size=2, max_size=6))
def test_back_to_back_frames_in_quick_reads_are_never_dropped(items: list[bytes]) -> None:
    # Each read arrives before the previous one's characters have all been spread.
    events = run(framer(), [(i, data) for i, data in enumerate(items)])
    assert frames(events) == items and faults(events) == []


@given(
    st.lists(frames_st, min_size=1, max_size=5),
    st.data(),
)
def test_one_corrupted_byte_is_one_crc_error_and_not_delivered(
    items: list[bytes], data: st.DataObject
) -> None:
    which = data.draw(st.integers(0, len(items) - 1))
    bad = bytearray(items[which])
    bad[data.draw(st.integers(0, len(bad) - 1))] ^= data.draw(st.integers(1, 255))
    sent = [*items[:which], bytes(bad), *items[which + 1 :]]
    chunks = [(i * 1_000_000, frame) for i, frame in enumerate(sent)]
    events = run(framer(), chunks)
    assert faults(events) == [(Counter.CRC_ERRORS, 1)]
    assert frames(events) == items[:which] + items[which + 1 :]


def test_gap_over_t15_breaks_the_frame_no_silence() -> None:
    # TES 6.2.3.2 01Dh: "not analysed frames by default of silent time".
    gap = 4 * CT + T15 + 1  # the second half starts T15 + 1 us after the first ends
    events = run(framer(), [(0, READ[:4]), (gap, READ[4:]), (FAR // 2, READ)])
    assert faults(events) == [(Counter.NO_SILENCE, 1)]
    assert frames(events) == [READ]


def test_gap_of_exactly_t15_keeps_the_frame() -> None:
    events = run(framer(), [(0, READ[:4]), (4 * CT + T15, READ[4:])])
    assert frames(events) == [READ]


def test_characters_until_t35_silence_belong_to_the_broken_frame() -> None:
    step = 4 * CT + 2 * T15  # every piece late, never t3.5 of silence
    chunks = [(i * step, READ[:4]) for i in range(5)]
    events = run(framer(), chunks)
    assert faults(events) == [(Counter.NO_SILENCE, 1)] and frames(events) == []


def test_a_short_frame_is_wrong_characters() -> None:
    # TES 6.2.3.2 01Bh: fewer than the 4 bytes of the shortest frame (TES 7.2.6).
    events = run(framer(), [(0, b"\x01\x03\x00")])
    assert faults(events) == [(Counter.WRONG_CHARACTERS, 3)]


def test_a_frame_followed_by_noise_keeps_the_frame() -> None:
    events = run(framer(), [(0, READ + b"\x55\xaa")])
    assert frames(events) == [READ]
    assert faults(events) == [(Counter.WRONG_CHARACTERS, 2)]


def test_noise_then_a_frame_back_to_back_is_one_crc_error() -> None:
    events = run(framer(), [(0, b"\x00\x00\x00\x00\x00" + READ)])
    assert faults(events) == [(Counter.CRC_ERRORS, 1)] and frames(events) == []


def test_eager_mode_hands_a_complete_frame_over_at_its_last_character() -> None:
    f = framer(TIMING.relaxed(50_000, eager=True))
    assert f.receive(READ[:5], 0) == []
    assert f.receive(READ[5:] + READ[:2], 10) == []
    assert state_of(f) is State.RECEIVING
    assert f.next_deadline() == 8 * CT
    assert f.poll(8 * CT) == [Frame(READ, 8 * CT)]
    assert f.receive(READ[2:], 10 * CT) == []
    assert f.state is State.IDLE
    assert f.poll(FAR) == [Frame(READ, 16 * CT)]
    assert f.next_deadline() is None


@given(st.lists(frames_st, min_size=1, max_size=6), st.lists(st.integers(1, 30), max_size=10))
def test_eager_mode_cuts_a_stream_without_timing(items: list[bytes], cuts: list[int]) -> None:
    stream, chunks, pos = b"".join(items), [], 0
    for cut in cuts:
        chunks.append((pos, stream[pos : pos + cut]))
        pos += cut
    chunks.append((pos, stream[pos:]))
    events = run(framer(TIMING.relaxed(50_000, eager=True)), chunks)
    assert frames(events) == items and faults(events) == []
    ends = [e.at for e in events]
    assert ends == sorted(ends)


@given(
    st.lists(
        st.tuples(st.integers(0, 3 * T35), st.binary(min_size=1, max_size=20)),
        max_size=20,
    )
)
def test_any_timed_byte_stream_is_framed_without_error(steps: list[tuple[int, bytes]]) -> None:
    f, at = framer(), 0
    chunks = []
    for gap, data in steps:
        at += gap
        chunks.append((at, data))
    events = run(f, chunks)
    assert all(crc_ok(e.data) for e in events if isinstance(e, Frame))
    assert f.state is State.IDLE and f.next_deadline() is None
