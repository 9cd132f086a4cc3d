"""The TES fault surface: faults by name, set and cleared like TSX module faults.

Line faults are aimed at one TES: on an RTU line with several TES, only the
faulty one stays silent, answers late or gets corrupted frames.
"""

from __future__ import annotations

import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.facade import fault_names, inject_fault
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.line import RtuLine
from fieldtwin.modbus.model import NO_REPLY, ExceptionCode, Link, ReadWords, Request
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.slave import Transmission
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.tes import Tes
from fieldtwin.transports.base import line_settings

from .helpers import read_word, read_words

TIMING = RtuTiming.from_format(line_settings(38400, 8, "E", 1))
CT, T35 = TIMING.char_us, TIMING.t35_us
CRC_ERRORS, GOOD_FRAMES = 0x01A, 0x01C  # §6.2.3.2 RS-485 counters of a TES 32EST


def _rtu(slave: int, request: Request) -> bytes:
    return with_crc(bytes((slave,)) + encode_request(request))


def _exchange(line: RtuLine, frame: bytes, at: int) -> list[Transmission]:
    line.receive(frame, at)
    out: list[Transmission] = []
    while (deadline := line.next_deadline()) is not None:
        out += line.poll(deadline)
    return out


def _line_of_three() -> tuple[RtuLine, list[Tes]]:
    clock = SimClock()
    tes = [Tes("TES 32EST", n, clock=clock) for n in (1, 2, 3)]
    return RtuLine(tes, Link.RS485, TIMING), tes


def _answers(line: RtuLine, at: int) -> dict[int, int | None]:
    """slave -> when its answer to a read left (None: no answer), for slaves 1..3."""
    out: dict[int, int | None] = {}
    for n in (1, 2, 3):
        frame = _rtu(n, ReadWords(3, 0, 1))
        replies = _exchange(line, frame, at + n * 10**6)
        out[n] = replies[0].at - (at + n * 10**6 + len(frame) * CT + T35) if replies else None
    return out


def test_fault_names_are_described_per_model() -> None:
    plain = fault_names(Tes("TES 8EA"))
    assert set(plain) == {
        "no_answer",
        "late_answer",
        "bad_crc",
        "broken_character",
        "not_ready",
        "drop_connections",
        "power_off",
    }
    assert all(isinstance(text, str) and text for text in plain.values())
    safety = fault_names(Tes("TES 32ET-S"))
    assert {"short_0", "open_0", "short_31", "open_31"} <= set(safety)
    assert "short_32" not in safety


def test_an_unknown_fault_or_parameter_names_what_is_allowed() -> None:
    tes = Tes("TES 32ET-S")
    with pytest.raises(ConfigError, match=r"unknown fault 'smoke' \(allowed: short_0\.\.short_31"):
        inject_fault(tes, "smoke", True)
    with pytest.raises(ConfigError, match=r"unknown fault 'short_3' \(allowed: no_answer"):
        inject_fault(Tes("TES 32ET"), "short_3", True)
    with pytest.raises(ConfigError, match=r"fault 'no_answer' takes no parameters, not ms"):
        inject_fault(tes, "no_answer", True, ms=3)
    with pytest.raises(ConfigError, match=r"late_answer' needs ms = 1\.\.60000"):
        inject_fault(tes, "late_answer", True)
    with pytest.raises(ConfigError, match=r"ms: 0 not allowed \(allowed 1\.\.60000 ms\)"):
        inject_fault(tes, "late_answer", True, ms=0)
    with pytest.raises(ConfigError, match=r"window_ms: 100 not allowed"):
        inject_fault(tes, "not_ready", True, window_ms=100)
    assert tes.active_faults() == {}


def test_no_answer_silences_only_the_faulty_tes_on_its_line() -> None:
    line, (one, two, three) = _line_of_three()
    inject_fault(two, "no_answer", True)
    assert _answers(line, 0) == {1: 0, 2: None, 3: 0}
    assert two.active_faults() == {"no_answer": {}}
    inject_fault(two, "no_answer", False)
    assert _answers(line, 10**7) == {1: 0, 2: 0, 3: 0}


def test_no_answer_executes_nothing() -> None:
    tes = Tes("TES 32EST")
    inject_fault(tes, "no_answer", True)
    assert read_words(tes, 0x000) is NO_REPLY
    inject_fault(tes, "no_answer", False)
    assert read_word(tes, 0x000) & 0x01  # power-on bit: nothing was read or written


def test_late_answer_delays_only_the_faulty_tes() -> None:
    line, (one, two, three) = _line_of_three()
    inject_fault(three, "late_answer", True, ms=25)
    assert _answers(line, 0) == {1: 0, 2: 0, 3: 25 * MS}
    assert three.active_faults() == {"late_answer": {"ms": 25.0}}
    inject_fault(three, "late_answer", False)
    assert three.answer_delay(Link.RS485) == 0


def test_bad_crc_is_aimed_at_one_tes_and_counted_by_all() -> None:
    line, (one, two, three) = _line_of_three()
    inject_fault(one, "bad_crc", True)
    assert _answers(line, 0) == {1: None, 2: 0, 3: 0}
    for tes in (one, two, three):
        assert tes.peek(CRC_ERRORS) == 1  # every TES heard the bad frame (§6.2.3.2 01Ah)
    inject_fault(one, "bad_crc", False)
    assert _answers(line, 10**7) == {1: 0, 2: 0, 3: 0}


def test_bad_crc_for_the_next_n_frames_clears_itself() -> None:
    line, (one, two, three) = _line_of_three()
    inject_fault(two, "broken_character", True, count=2)
    assert two.active_faults() == {"broken_character": {"count": 2}}
    assert _answers(line, 0)[2] is None
    assert _answers(line, 10**7)[2] is None
    assert _answers(line, 2 * 10**7)[2] == 0
    assert two.active_faults() == {}


def test_not_ready_always_for_n_or_in_the_refresh_window() -> None:
    tes = Tes("TES 32EST")
    inject_fault(tes, "not_ready", True)
    assert read_words(tes, 0x025) is ExceptionCode.SLAVE_DEVICE_FAILURE  # 32-bit area
    assert isinstance(read_words(tes, 0x000), tuple)  # never below it (AMB-TES-28)
    inject_fault(tes, "not_ready", True, count=1)
    assert read_words(tes, 0x025) is ExceptionCode.SLAVE_DEVICE_FAILURE
    assert isinstance(read_words(tes, 0x025), tuple)
    inject_fault(tes, "not_ready", True, window_ms=2)
    assert tes.not_ready_window_us == 2 * MS
    assert read_words(tes, 0x025) is ExceptionCode.SLAVE_DEVICE_FAILURE  # 0 ms into the 100 ms
    tes.advance(0.003)
    assert isinstance(read_words(tes, 0x025), tuple)
    inject_fault(tes, "not_ready", False)
    assert tes.not_ready_window_us == 0 and tes.active_faults() == {}


def test_power_off_and_on_by_name() -> None:
    tes = Tes("TES 8EA")
    inject_fault(tes, "power_off", True)
    assert not tes.powered and tes.leds["Pwr"] == "off"
    assert tes.active_faults() == {"power_off": {}}
    assert read_words(tes, 0x000) is NO_REPLY
    inject_fault(tes, "power_off", False)
    assert tes.powered and read_word(tes, 0x000) & 0x01  # §6.4.1 bit 0 after power-on


def test_wiring_faults_by_name_like_the_plant_keys() -> None:
    tes = Tes("TES 32ET-S")
    tes.write_eeprom({"security_inputs": 0xFFFFFFFF})
    tes.power_cycle()
    inject_fault(tes, "short_3", True)
    inject_fault(tes, "open_17", True)
    assert tes.peek(0x1A5) == 1 << 3 and tes.peek(0x1A8) == 1 << 1  # §6.2.7 SC / OC words
    assert tes.active_faults() == {"short_3": {}, "open_17": {}}
    inject_fault(tes, "open_3", False)  # not the fault input 3 has: unchanged
    assert tes.peek(0x1A5) == 1 << 3
    inject_fault(tes, "short_3", False)
    inject_fault(tes, "open_17", False)
    assert tes.peek(0x1A9) == 0 and tes.peek(0x1AA) == 0


def test_drop_connections_is_refused_where_no_tcp_endpoint_serves_the_tes() -> None:
    tes = Tes("TES 8EA")
    with pytest.raises(ConfigError, match="not served on a TCP endpoint"):
        inject_fault(tes, "drop_connections", True)
    closed: list[str] = []
    tes.line_faults.droppers.append(lambda: closed.append("x") or 1)
    inject_fault(tes, "drop_connections", True)
    inject_fault(tes, "drop_connections", False)  # a one-shot: clearing does nothing
    assert closed == ["x"] and "drop_connections" not in tes.active_faults()
