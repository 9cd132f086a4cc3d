"""SCM 5 / 6 / 7: register words, discrete bits, power, additional requests, faults, variants."""

from __future__ import annotations

import pytest

from fieldtwin.devices.scm import ScmDevice
from fieldtwin.devices.scm.plantkeys import signal_text
from fieldtwin.devices.scm.status import lines as status_lines
from fieldtwin.errors import ConfigError
from fieldtwin.facade import inject_fault
from fieldtwin.live import mode
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm import MODULE_TYPES, VARIANTS
from tests.tsx.scm.helpers import (
    CHAR_US_9600_8N2,
    CONFIG_3_3,
    PLAIN_HD,
    SLOT,
    fault_bits,
    m,
    make,
    ready,
)


def test_7_3_every_reference_is_a_module_type() -> None:
    assert len(MODULE_TYPES) == 19 and set(MODULE_TYPES) == set(VARIANTS)
    assert {"TSX SCM 2011", "TSX SCM 2244", "TSX SCM 2111", "TSX SCM 2146"} <= set(MODULE_TYPES)


@pytest.mark.parametrize(
    "ref,code", [("TSX SCM 2011", 696), ("TSX SCM 2113", 697), ("TSX SCM 2244", 698)]
)
def test_1_2_configuration_codes(ref: str, code: int) -> None:
    plc, mod = make(ref, code=code)
    assert plc.read("I7,S") == 0
    plc, mod = make(ref, code=code + 1 if code != 698 else 696)
    assert plc.read("I7,S") == 1
    plc, mod = make(ref, slot=3, model="TSX 47-20", code=63)
    assert plc.read("I3,S") == 0


def test_5_2_adaptor_codes_in_iw1() -> None:
    # 2013: channel 0 SCA1 (001), channel 1 SCA3 (101); AMB-SCM-8 bit 6 / E is the MSB
    plc, mod = make("TSX SCM 2013")
    word = plc.read("IW7,1")
    assert (word >> 4) & 7 == 0b001 and (word >> 12) & 7 == 0b101
    plc, mod = make("TSX SCM 2011", adaptors=["SCA4", "none"])
    word = plc.read("IW7,1")
    assert (word >> 4) & 7 == 0b011 and (word >> 12) & 7 == 0b111
    with pytest.raises(ConfigError):
        mod.attach(1, "memory")


def test_5_2_iw0_c_and_iw1_run_bits_follow_a_request() -> None:
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x04, send=[3], recv_bytes=4)
    plc.advance(0.03)
    assert plc.read("IW7,0,C") == 1 and plc.read("IW7,1,1") == 1 and plc.read("IW7,1,2") == 0
    peer.send(b"abc")
    plc.advance(0.03)
    assert tb.done and plc.read("IW7,0,C") == 0 and plc.read("IW7,1,1") == 0


def test_5_1_cts_inhibits_transmission_and_cd_reception() -> None:
    plc, mod, peer = ready()
    mod.set_signal(0, "CTS", 1)
    tb = plc.start_exchange(m=m(0), c=0x01, send_bytes=b"hi")
    plc.advance(0.2)
    assert peer.receive() == b"" and not tb.done
    signal_text(mod, 0, "CTS=0")
    plc.advance(0.02)
    assert tb.done and peer.receive() == b"hi"
    assert plc.read("I7,8") == 0 and plc.read("I7,9") == 0


def test_5_1_sca3_unused_signals_lock_the_channel_and_dsrs_halves_speed() -> None:
    plc, mod = make("TSX SCM 2013")
    peer = mod.attach_memory(1)
    plc.exchange(m=m(1), c=0x40, send=PLAIN_HD)
    assert [plc.read(f"I7,{b}") for b in "CDEF"] == [1, 1, 1, 1]  # pulled up: locked
    tb = plc.start_exchange(m=m(1), c=0x01, send_bytes=b"ab")
    plc.advance(0.1)
    assert not tb.done
    plc.write("O7,5", 1)  # DSRS: half speed
    plc.advance(0.02)
    mod.set_signal(1, "CTS", 0)
    mod.set_signal(1, "CD", 0)
    plc.advance(0.05)
    assert tb.done
    times = [t for t, _ in peer.log]
    assert times[1] - times[0] == 2 * CHAR_US_9600_8N2


def test_5_1_sca2_psr_image() -> None:
    plc, mod = make("TSX SCM 2022")
    plc.write("O7,0", 1)
    plc.advance(0.02)
    assert plc.read("I7,8") == 1
    with pytest.raises(ConfigError):
        mod.set_signal(0, "CTS", 0)


def test_6_2_pwf_after_power_break_and_its_acknowledgement() -> None:
    plc, mod, peer = ready(words=CONFIG_3_3)
    assert plc.read("IW7,1,F") == 0
    plc.start_exchange(m=m(0), c=0x04, send=[5], recv_bytes=6)
    plc.advance(0.03)
    plc.power_break(1.0)
    plc.advance(1.1)
    assert plc.read("IW7,1,F") == 1 and plc.read("IW7,1,3") == 1  # configuration kept
    assert fault_bits(plc) >> 39 & 1  # PWF without init during exchange, channel 0
    plc.write("OW7,1,F", 1)
    plc.advance(0.02)
    assert plc.read("IW7,1,F") == 0


def test_4_5_system_error_codes() -> None:
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x04, send=[5], recv_bytes=6, txt=3)
    plc.advance(0.02)
    second = plc.exchange(m=m(0), c=0x04, send=[5], recv_bytes=6, txt=4)
    assert (second.e, second.s) == (True, 5)  # too many active Text Blocks
    plc.write("OW7,1,1", 1)  # reset exchange channel 0
    plc.advance(0.03)
    assert tb.result is not None and (tb.result.e, tb.result.s) == (True, 1)
    plc.write("OW7,1,1", 0)
    too_long = plc.exchange(m=m(0), c=0x01, send_bytes=b"x" * 256)
    assert (too_long.e, too_long.s) == (True, 2)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[5], recv_bytes=6, txt=5)
    plc.advance(0.02)
    plc.power_break(0.5)
    assert tb.result is not None and tb.result.s == 3  # power break during the exchange
    plc.advance(1.1)
    small = plc.exchange(m=0x0763, c=0x0F, recv_bytes=10)
    assert (small.e, small.s) == (True, 6)  # message longer than planned
    plc.remove(0, SLOT)
    gone = plc.exchange(m=m(0), c=0x01, send_bytes=b"x")
    assert (gone.e, gone.s) == (True, 4)


def test_5_2_message_system_reset() -> None:
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x04, send=[5], recv_bytes=6)
    plc.advance(0.02)
    plc.write("OW7,0,2", 1)
    plc.advance(0.03)
    assert tb.result is not None and tb.result.s == 1 and plc.read("IW7,0,2") == 1
    plc.write("OW7,0,2", 0)
    plc.advance(0.02)
    assert plc.read("IW7,0,2") == 0 and plc.read("IW7,1,1") == 0


def test_6_3_identification_application_name_module_reset() -> None:
    plc, mod, peer = ready(words=CONFIG_3_3)
    ident = plc.exchange(m=0x0763, c=0x0F, recv_bytes=27)
    assert (ident.v, ident.s) == (0x3F, 27) and ident.data.startswith(b"TSX SCM 2011 V1.3")
    assert plc.exchange(m=0x0763, c=0x49, send_bytes=b"LINE 3 PRINTER").v == 0xFE
    plc.power_break(2.0)
    plc.advance(1.1)
    name = plc.exchange(m=0x0763, c=0x4A, recv_bytes=20)
    assert (name.v, name.s) == (0x7A, 20) and name.data.rstrip() == b"LINE 3 PRINTER"
    reset = plc.exchange(m=0x0763, c=0x44)
    assert (reset.v, reset.s) == (0xFE, 0)
    assert plc.read("IW7,0,9") == 1  # self-test again
    plc.advance(1.1)
    assert plc.read("IW7,1,3") == 0 and plc.read("IW7,0,B") == 1 and plc.read("IW7,1,F") == 0


def test_6_1_self_test_faults() -> None:
    plc = Plc()
    mod = plc.insert("TSX SCM 2011", rack=0, slot=SLOT)
    inject_fault(mod, "loopback_ch1", True)
    inject_fault(mod, "rts_cts_ch1", True)
    plc.advance(1.1)
    assert plc.read("IW7,0,6") == 1 and plc.read("I7,S") == 1 and plc.read("IW7,0,3") == 1
    bits = fault_bits(plc)
    assert bits >> 24 & 1 and bits >> 26 & 1 and not bits >> 16 & 1
    inject_fault(mod, "ram", True)
    plc.advance(0.02)
    assert plc.read("IW7,0,8") == 1 and plc.read("IW7,0,4") == 1 and mod.leds["F"] == "on"


def test_6_3_parity_fault_from_a_peer_with_another_format() -> None:
    plc, mod, peer = ready(words=[0x0711, 0x9600, 0, 0, 0, 0, 0, 0])  # 7 bits odd 1 stop
    peer.set_format(7, "E", 1)  # the peer uses even parity
    tb = plc.start_exchange(m=m(0), c=0x04, send=[2], recv_bytes=2)
    plc.advance(0.02)
    peer.send(b"AC")
    plc.advance(0.02)
    assert tb.result is not None and tb.result.data == b"AC"
    assert fault_bits(plc) >> 37 & 1  # reception parity fault, channel 0
    assert plc.read("I7,S") == 0  # SCM 7.1: application faults no longer set Ixy,S


def test_6_3_format_fault_on_21_full_duplex_and_injected() -> None:
    plc, mod = make("TSX SCM 2111")
    peer = mod.attach_memory(1)
    plc.exchange(m=m(1), c=0x40, send=[0x1802, 0x9600, 0, 0, 0, 0, 0, 0, 0])
    peer.set_format(8, "N", 1, baud=4800)  # half the speed: stop bits sampled at 0
    peer.send(b"\x00")
    plc.advance(0.03)
    assert fault_bits(plc) >> 46 & 1  # 21: 3rd word bit E, format fault in reception
    inject_fault(mod, "parity_ch1", True)
    peer.set_format(8, "N", 2)
    peer.send(b"x")
    plc.advance(0.03)
    assert fault_bits(plc) >> 45 & 1
    with pytest.raises(ConfigError):
        inject_fault(mod, "nonsense", True)


def test_1_2_status_shows_no_run_stop_mode() -> None:
    # SCM 1.2: an OK and an F light only; 5.2 IWxy,0,C "A request is being executed"
    # (AMB-SCM-26): the module has no Run/Stop mode, status and the live view show none
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x04, send=[5], recv_bytes=5)
    plc.advance(0.02)
    assert plc.read("IW7,0,C") == 1 and mod.active and not mod.running
    status = status_lines(mod)
    assert "mode" not in status and status["activity"] == "executing a request"
    device = ScmDevice(mod, plc)
    assert device.status().mode is None and mode(device.status()) == "operational"
    peer.send(b"12345")
    plc.advance(0.03)
    assert tb.done and status_lines(mod)["activity"] == "awaiting a request"
    assert mode(device.status()) == "operational" and "Stop" not in mode(device.status())
