"""The common part of every intelligent module, through the test double."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError, ProtocolError
from fieldtwin.facade import inject_fault
from fieldtwin.tsx.messages import Exchanges
from fieldtwin.tsx.module import FaultCategory, ModuleEvent, ModuleState
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.textblock import Answer, Exchange, Request
from fieldtwin.tsx.txt import TxtState
from tests.tsx.double import CONVERTER, DOUBLE, SENSOR, TERMINAL_BLOCK, Double

M = 0x0563  # rack 0 slot 5, module system


def make(model: str = "TSX 87", code: int | None = None) -> tuple[Plc, Double]:
    plc = Plc(model=model, scan_ms=10)
    mod = plc.insert(DOUBLE, rack=0, slot=5 if model != "TSX 47-20" else 3, code=code)
    return plc, mod


def test_initial_self_test_bits_and_leds() -> None:
    # AEM 7.1-1: during the self-test IWxy,0,9 = 1, ERR and OK lit; then IWxy,0,3 = 1
    plc, mod = make()
    plc.advance(0.05)
    assert plc.read("IW5,0,9") == 1 and plc.read("IW5,0,3") == 0
    assert mod.leds == {"OK": "on", "ERR": "on", "F": "off"}
    plc.advance(2.0)
    assert plc.read("IW5,0,9") == 0 and plc.read("IW5,0,3") == 1
    assert mod.leds == {"OK": "on", "ERR": "off", "F": "off"}
    assert plc.read("I5,S") == 0


def test_run_stop_follows_the_command_bit() -> None:
    # AEM 2.5-2: OWxy,0,C commands Run/Stop, IWxy,0,C shows it
    plc, mod = make()
    plc.advance(2.1)
    assert plc.read("IW5,0,C") == 0
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    assert plc.read("IW5,0,C") == 1 and mod.running
    plc.write("OW5,0,C", 0)
    plc.advance(0.02)
    assert plc.read("IW5,0,C") == 0


def test_awaiting_configuration_blocks_run() -> None:
    plc, mod = make()
    plc.advance(2.1)
    mod.awaiting_configuration = True
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    assert plc.read("IW5,0,B") == 1 and plc.read("IW5,0,C") == 0


def test_application_fault_latches_until_the_fault_string_is_read() -> None:
    # AEM 4.4-1: IWxy,0,4 and 7 stay at 1 after the fault disappears, until read
    plc, mod = make()
    plc.advance(2.1)
    plc.write("OW5,0,C", 1)
    inject_fault(mod, "sensor", True)
    plc.advance(0.02)
    assert (plc.read("IW5,0,4"), plc.read("IW5,0,7")) == (1, 1)
    assert mod.leds["ERR"] == "on" and plc.read("I5,S") == 0 and mod.running  # keeps running
    inject_fault(mod, "sensor", False)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 1 and mod.leds["ERR"] == "off"  # memorised, LED live
    r = plc.exchange(m=M, c=0x47, recv_bytes=8)
    assert r.v == 0x77 and r.s == 8 and r.data[SENSOR // 8] == 1 << (SENSOR % 8)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 0 and plc.read("IW5,0,4") == 0


def test_fault_read_while_present_clears_when_the_fault_ends() -> None:
    plc, mod = make()
    plc.advance(2.1)
    inject_fault(mod, "sensor", True)
    plc.exchange(m=M, c=0x47, recv_bytes=8)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 1  # still present
    inject_fault(mod, "sensor", False)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 0


def test_second_fault_not_reported_until_the_first_is_gone() -> None:
    # AEM 4.4-1: "The message read after detection of fault nbr. 1 will not contain
    # fault nbr. 2 ... IWxy,0,4 and IWxy,0,i are at 1 until fault nbr. 1 disappears."
    plc, mod = make()
    plc.advance(2.1)
    mod.set_fault(SENSOR, True)
    first = plc.exchange(m=M, c=0x47, recv_bytes=8)
    mod.set_fault(SENSOR + 4, True)  # fault 2 while fault 1 is present
    assert first.data[4] == 0x01
    mod.set_fault(SENSOR, False)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 1  # fault 2 not acknowledged yet
    second = plc.exchange(m=M, c=0x47, recv_bytes=8)
    assert second.data[4] == 0x10
    mod.set_fault(SENSOR + 4, False)
    plc.advance(0.02)
    assert plc.read("IW5,0,7") == 0


def test_module_fault_stops_the_module_and_sets_the_fault_bit() -> None:
    # AEM 2.5-4: an acquisition/conversion fault stops the module until it disappears
    plc, mod = make()
    plc.advance(2.1)
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    inject_fault(mod, "terminal_block", True)
    plc.advance(0.02)
    assert plc.read("IW5,0,C") == 0 and plc.read("I5,S") == 1
    assert plc.read("IW5,0,A") == 1 and plc.read("IW5,0,6") == 1
    assert mod.leds["OK"] == "off"
    inject_fault(mod, "terminal_block", False)
    plc.advance(0.02)
    assert plc.read("IW5,0,C") == 1 and plc.read("I5,S") == 0 and plc.read("IW5,0,A") == 0
    assert plc.read("IW5,0,6") == 1  # memorised until the fault string is read


def test_blocking_fault_takes_the_module_out_of_service() -> None:
    plc, mod = make()
    plc.advance(2.1)
    mod.set_fault(0, True)
    plc.advance(0.02)
    assert mod.state is ModuleState.BLOCKED
    assert plc.read("IW5,0,8") == 1 and plc.read("I5,S") == 1
    assert mod.leds == {"OK": "off", "ERR": "off", "F": "on"}
    r = plc.exchange(m=M, c=0x0F, recv_bytes=27)
    assert r.e and r.s == 4  # module fault


def test_blocking_fault_ends_held_exchanges_as_module_fault() -> None:
    plc, mod = make()
    plc.advance(2.1)
    tb = plc.start_exchange(m=M, c=0x02)
    plc.advance(0.05)
    assert mod.held and not tb.done
    mod.set_fault(0, True)
    plc.advance(0.02)
    assert tb.result is not None and tb.result.e and tb.result.s == 4


def test_hardware_fault_found_by_the_initial_self_test() -> None:
    plc, mod = make()
    mod.hardware_fault(CONVERTER)
    plc.advance(2.1)
    assert plc.read("IW5,0,6") == 1 and plc.read("I5,S") == 1
    plc.power_break(1.0)
    plc.advance(2.1)
    assert plc.read("I5,S") == 1  # still there at the next power-up


def test_wrong_declared_code_sets_the_fault_bit() -> None:
    plc, mod = make(code=901)
    plc.advance(2.1)
    assert plc.read("I5,S") == 1 and plc.read("IW5,0,8") == 1  # "incorrectly coded"
    assert "declared code" in mod.status()["code"]
    plc2, _ = make(code=900)
    plc2.advance(2.1)
    assert plc2.read("I5,S") == 0 and plc2.read("IW5,0,8") == 0
    plc3, _ = make(model="TSX 47-20", code=90)
    plc3.advance(2.1)
    assert plc3.read("I3,S") == 0


def test_removal_and_insertion_under_power() -> None:
    plc, mod = make()
    plc.advance(2.1)
    plc.remove(0, 5)
    plc.advance(0.02)
    assert plc.read("I5,S") == 1 and plc.read("IW5,0") == 0x0100  # bit 8: module absent
    assert mod.leds == {"OK": "off", "ERR": "off", "F": "off"}
    plc.reinsert(0, 5)
    plc.advance(0.02)
    assert plc.read("IW5,0,9") == 1  # self-test again
    assert mod.power_ups == 2


def test_short_power_break_does_not_restart_the_modules() -> None:
    plc, mod = make()
    plc.advance(2.1)
    plc.power_break(0.005)
    assert mod.power_ups == 1
    plc.power_break(0.5)
    assert mod.power_ups == 2


def test_message_system_reset_cancels_the_exchange_in_progress() -> None:
    plc, mod = make()
    plc.advance(2.1)
    tb = plc.start_exchange(m=M, c=0x02, recv_bytes=0)
    plc.advance(0.05)
    assert mod.held and not tb.done
    plc.write("OW5,0,2", 1)
    plc.advance(0.05)
    assert plc.read("IW5,0,2") == 1
    assert tb.done and tb.result is not None and tb.result.e and tb.result.s == 1
    plc.write("OW5,0,2", 0)
    plc.advance(0.02)
    assert plc.read("IW5,0,2") == 0


def test_common_requests() -> None:
    plc, mod = make()
    plc.advance(2.1)
    v = plc.exchange(m=M, c=0x0F, recv_bytes=27)
    assert (v.v, v.s) == (0x3F, 27) and v.data.startswith(b"TEST DOUBLE V1.0")
    w = plc.exchange(m=M, c=0x49, send_bytes=b"TANK 3")
    assert (w.v, w.s, w.e) == (0xFE, 0, False)
    r = plc.exchange(m=M, c=0x4A, recv_bytes=20)
    assert (r.v, r.s) == (0x7A, 20) and r.data == b"TANK 3".ljust(20)
    too_long = plc.exchange(m=M, c=0x49, send_bytes=b"x" * 21)
    assert too_long.v == 0xFD
    assert plc.exchange(m=M, c=0x49, send_bytes=b"").v == 0xFD
    assert plc.exchange(m=M, c=0x55).v == 0xFD  # unknown request


def test_requests_during_self_test_are_held_until_it_ends() -> None:
    plc, mod = make()
    r = plc.exchange(m=M, c=0x0F, recv_bytes=27)
    assert r.v == 0x3F and r.ended_at_us >= 2_000_000


def test_state_machine_rejects_an_impossible_event() -> None:
    plc, mod = make()
    with pytest.raises(ProtocolError, match="can't handle 'power on' in state self-test"):
        mod.power_on()
    plc.advance(2.1)
    with pytest.raises(ProtocolError, match="'self-test done' in state operational"):
        mod._fire(ModuleEvent.SELF_TEST_DONE, plc.now)


def test_inject_unknown_fault_names_the_allowed_ones() -> None:
    plc, mod = make()
    with pytest.raises(ConfigError, match="allowed: terminal_block, sensor"):
        inject_fault(mod, "smoke", True)


def test_blocking_fault_during_the_self_test_ends_it_blocked() -> None:
    # AEM 7.1-1: a processing-circuit fault leaves the module out of service; the end
    # of the self-test must not bring it back (it raised ProtocolError from the clock)
    plc, mod = make()
    plc.advance(0.5)
    mod.set_fault(0, True)
    plc.advance(3.0)
    assert mod.state is ModuleState.BLOCKED
    assert plc.read("IW5,0,8") == 1 and plc.read("IW5,0,3") == 0 and plc.read("IW5,0,9") == 0


def test_outputs_reach_the_module_again_after_a_long_power_break() -> None:
    # AEM 2.5-3: the module restarts from nothing; the PLC's output image is the same,
    # so the first refresh after power return must still deliver it
    plc, mod = make()
    plc.advance(2.1)
    plc.write("OW5,1", 5)
    plc.write("O5,1", 1)
    plc.advance(0.02)
    assert plc.read("I5,0") == 1
    plc.power_break(0.5)
    plc.advance(2.1)
    assert (plc.read("I5,0"), plc.read("IW5,1"), mod.o_bits) == (1, 5, 0b10)


# --- property: any sequence of events ends in a legal state (DESIGN rule 12) ---------

_BITS = (0, TERMINAL_BLOCK, CONVERTER, SENSOR, SENSOR + 9)  # blocking, module x2, app x2
_OPS = st.one_of(
    st.tuples(st.just("advance"), st.sampled_from((0.004, 0.01, 0.5, 2.5))),
    st.tuples(st.just("break"), st.sampled_from((0.005, 0.5))),
    st.tuples(st.sampled_from(("remove", "reinsert", "cold", "stop", "start")), st.just(0)),
    st.tuples(st.just("fault"), st.sampled_from(_BITS), st.booleans()),
    st.tuples(st.just("hardware"), st.sampled_from((0, CONVERTER)), st.booleans()),
    st.tuples(st.just("write"), st.sampled_from(("OW5,0,C", "OW5,0,2")), st.integers(0, 1)),
    st.tuples(st.just("txt"), st.integers(0, 2), st.sampled_from((0x47, 0x0F, 0x02))),
    st.tuples(st.just("reset"), st.integers(0, 2)),
)


def _apply(plc: Plc, mod: Double, op: tuple[Any, ...]) -> None:
    kind = op[0]
    simple = {"remove": lambda: plc.remove(0, 5), "reinsert": lambda: plc.reinsert(0, 5)}
    simple |= {"cold": plc.cold_restart, "stop": plc.stop, "start": plc.start}
    if kind in simple:
        simple[kind]()
    elif kind == "advance":
        plc.advance(op[1])
    elif kind == "break":
        plc.power_break(op[1])
    elif kind == "fault":
        mod.set_fault(op[1], op[2])
    elif kind == "hardware":
        mod.hardware_fault(op[1], op[2])
    elif kind == "write":
        plc.write(op[1], op[2])
    elif kind == "txt" and plc.text_block(op[1]).state in (TxtState.IDLE, TxtState.DONE):
        plc.start_exchange(m=M, c=op[2], recv_bytes=27, txt=op[1])
    elif kind == "reset":
        plc.reset_text_block(op[1])


def _panel(ok: bool, err: bool, f: bool) -> dict[str, str]:
    return {name: "on" if lit else "off" for name, lit in (("OK", ok), ("ERR", err), ("F", f))}


def _check_status_word(mod: Double) -> None:
    state, word = mod.state, mod.iw[0]
    bit = lambda n: bool(word >> n & 1)  # noqa: E731
    if state is ModuleState.OFF:
        assert (
            word == 0 and mod.leds == {"OK": "off", "ERR": "off", "F": "off"} and mod.module_fault
        )
        return
    module_fault = mod._faults.any(FaultCategory.MODULE, memorised=False)
    application = mod._faults.any(FaultCategory.APPLICATION, memorised=False)
    assert bit(9) == (state is ModuleState.SELF_TEST)
    assert bit(3) == (state is ModuleState.OPERATIONAL)
    assert bit(8) == (state is ModuleState.BLOCKED)
    assert bit(4) == (bit(6) or bit(7))
    assert bit(6) or not module_fault
    assert bit(7) or not application
    assert bit(0xA) == mod.fault_active(TERMINAL_BLOCK)
    assert not bit(0xC) or (state is ModuleState.OPERATIONAL and not module_fault)
    assert not bit(0xC) or mod.ow[0] >> 0xC & 1
    blocked = state is ModuleState.BLOCKED
    assert mod.module_fault == (blocked or module_fault)
    if state is ModuleState.OPERATIONAL:
        assert mod.leds == _panel(not module_fault, application, False)
    else:
        assert mod.leds == (_panel(False, False, True) if blocked else _panel(True, True, False))


@settings(max_examples=150)
@given(st.lists(_OPS, max_size=25))
def test_any_sequence_of_events_ends_in_a_legal_state(ops: list[tuple[Any, ...]]) -> None:
    plc, mod = make()
    for op in ops:
        _apply(plc, mod, op)
        plc.advance(0.01)
        _check_status_word(mod)
    # clean up: module back, faults gone and acknowledged, PLC in RUN: then the module
    # is ready with no memorised fault, and no channel is left stuck with an exchange
    for bit in _BITS[1:]:
        mod.set_fault(bit, False)
    mod.hardware_fault(0, False)
    mod.hardware_fault(CONVERTER, False)
    plc.reinsert(0, 5)
    plc.start()
    if mod.state is ModuleState.BLOCKED:
        plc.power_break(0.5)
    for txt in range(3):
        plc.reset_text_block(txt)
    plc.advance(2.1)
    assert not plc.exchange(m=M, c=0x47, recv_bytes=8, txt=3).e
    plc.advance(0.02)
    _check_status_word(mod)
    assert plc.read("IW5,0") & 0x03D8 == 0x0008  # ready: no fault, no self-test


def test_a_second_completion_of_an_exchange_raises() -> None:
    # issue 9 item 4: it was silently ignored, which hid dead code in the AEM
    exchange = Exchange(Request(0x0F, 0x63, b"", 27), 0, lambda e, at: None)
    exchange.complete(Answer(0x3F), 5)
    with pytest.raises(ProtocolError, match="C=0F channel 63: can't complete it twice"):
        exchange.complete(Answer.fault(1), 6)
    assert exchange.answer == Answer(0x3F)


def test_the_message_interface_is_a_component_the_module_holds() -> None:
    plc, mod = make()
    assert isinstance(mod.exchanges, Exchanges)
    tb = plc.start_exchange(m=M, c=0x0F, recv_bytes=27)
    plc.advance(0.011)  # validated, held by the self-test
    held = mod.exchanges.pending(0x63)
    assert held is not None and mod.exchanges.held() == [held] and not tb.done
    plc.advance(2.1)
    assert tb.done and mod.exchanges.pending(0x63) is None
