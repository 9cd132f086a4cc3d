"""§6 every documented word of every model, through `fieldtwin run` and pymodbus.

Table-driven from ``fieldtwin.tes.memmap``: slaves 1..10 hold one TES of each
model (1..5 on Modbus TCP, 6..10 on pty line A).  Every word is read (fc 03,
and fc 04 on the first block); every writable word is written (fc 06 or 10)
and read back, then restored; every read-only word refuses a write with
exception 2 (§7.2 error codes, AMB-TES-01).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from fieldtwin.tes.memmap import Access, Register, memory_map
from fieldtwin.tes.models import Family, model_named
from tests.tes.blackbox.conftest import (
    MAP_TES,
    client_for,
    exception_code,
    words,
    write,
)

SLAVES = sorted(MAP_TES)
PAIR_KINDS = ("counter_rise", "counter_fall", "duration_1", "duration_0")
PAIR_KINDS_CUMULATED = ("cumulated_1", "cumulated_0")

pytestmark = pytest.mark.timeout(30)  # every test bounded, setup included


def _map(slave: int) -> tuple[Register, ...]:
    return memory_map(model_named(MAP_TES[slave]))


def _runs(regs: tuple[Register, ...], limit: int = 125) -> Iterator[list[Register]]:
    """Contiguous runs of documented words, at most ``limit`` long (one request each)."""
    run: list[Register] = []
    for reg in regs:
        if run and (reg.address != run[-1].address + 1 or len(run) == limit):
            yield run
            run = []
        run.append(reg)
    if run:
        yield run


def _expected_on_read(reg: Register, value: int) -> None:
    """What the manual fixes for a fresh TES with no input signals."""
    if reg.kind == "zero" or not reg.fitted:
        assert value == 0, reg  # reserved / not used words, channels the model lacks
    elif reg.kind == "filter":
        assert value == 1, reg  # §3.1.2 filtering time 5 ms, Tb = 5 ms
    elif reg.kind == "blink":
        assert value == (100, 100, 10, 10)[reg.index], reg  # §3.1.2 1 Hz and 10 Hz
    elif reg.kind in ("watchdog", "analog_input", "history", "fallback_value"):
        assert value == 0, reg  # no watching; 0 V inputs; analog outputs without fallback
    elif reg.kind in ("counter_rise", "counter_fall"):
        assert value == 0, reg  # no input changed since power-on


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_6_every_documented_word_reads(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    regs = _map(slave)
    for run in _runs(regs):
        values = words(client, slave, run[0].address, len(run))
        for reg, value in zip(run, values, strict=True):
            _expected_on_read(reg, value)
    # AMB-TES-04: fc 04 reads the same memory as fc 03
    first = next(_runs(regs))
    stable = [i for i, r in enumerate(first) if r.access is Access.MP or r.kind == "zero"]
    by_04 = client.read_input_registers(first[0].address, count=len(first), device_id=slave)
    by_03 = words(client, slave, first[0].address, len(first))
    assert [by_04.registers[i] for i in stable] == [by_03[i] for i in stable]


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_7_2_words_past_the_map_are_exception_2(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    last = _map(slave)[-1].address
    reply = client.read_holding_registers(last + 1, count=1, device_id=slave)
    assert exception_code(reply) == 2
    reply = client.read_holding_registers(last - 1, count=3, device_id=slave)
    assert exception_code(reply) == 2  # a span that runs off the map
    reply = client.write_register(last + 1, 0, device_id=slave)
    assert exception_code(reply) == 2


def _test_value(reg: Register) -> int:
    return (0x1234 + 0x11 * reg.address) & 0x7FFF


def _check_written(slave: int, reg: Register, value: int, got: int) -> None:
    family = model_named(MAP_TES[slave]).family
    if reg.kind.startswith("diag_"):
        assert value <= got <= value + 3, reg  # the counter goes on counting frames
    elif reg.kind in PAIR_KINDS + PAIR_KINDS_CUMULATED and not reg.fitted:
        assert got == 0, reg  # AMB-TES-13: writes to channels a model lacks are ignored
    elif reg.kind.startswith(("duration_0", "cumulated_0")) and reg.index % 2:
        assert value <= got <= value + 20, reg  # state 0 is running: the chronometer goes on
    elif reg.kind == "command" and family is Family.ANALOG:
        assert got == value & 0x0F0F, reg  # §6.4.5 bits 11-08 blinking, 03-00 states
    else:
        assert got == value, reg


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_6_every_writable_word_is_written_and_read_back(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    writable = tuple(r for r in _map(slave) if r.access.writable and r.kind != "status")
    for run in _runs(writable, limit=123):
        old = words(client, slave, run[0].address, len(run))
        values = [_test_value(r) for r in run]
        write(client, slave, run[0].address, *values)  # fc 10 (fc 06 for a single word)
        back = words(client, slave, run[0].address, len(run))
        for reg, value, got in zip(run, values, back, strict=True):
            _check_written(slave, reg, value, got)
        write(client, slave, run[0].address, *old)
        first = run[0]  # fc 06 on the first word of the run
        write(client, slave, first.address, _test_value(first) ^ 1)
        _check_written(slave, first, _test_value(first) ^ 1, *words(client, slave, first.address))
        write(client, slave, first.address, old[0])


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_6_every_read_only_word_refuses_a_write(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    for reg in _map(slave):
        # on the pty, one history word in ten (the rest are read-only by the same rule)
        sampled = reg.kind != "history" or client is tcp or reg.index % 10 == 0
        if reg.access is Access.R and sampled:
            reply = client.write_register(reg.address, 0, device_id=slave)
            assert exception_code(reply) == 2, reg


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_6_status_bits_are_reset_by_the_master_not_set(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    family = model_named(MAP_TES[slave]).family
    write(client, slave, 0x000, 0xFFFF)  # a master write cannot set TES bits (AMB-TES-09)
    (status,) = words(client, slave, 0x000)
    assert status & 0x0006 == 0  # no fallback (no watching), no wiring default
    write(client, slave, 0x000, 0x0000)
    (status,) = words(client, slave, 0x000)
    assert status & 0x0007 == 0, family  # bits 0..2 reset by the master


@pytest.mark.parametrize("slave", SLAVES, ids=[MAP_TES[s] for s in SLAVES])
def test_section_7_1_2_bit_address_is_word_times_16_plus_bit(
    slave: int, tcp: ModbusTcpClient, line_a: ModbusSerialClient
) -> None:
    client = client_for(slave, tcp, line_a)
    reg = next(r for r in _map(slave) if r.kind == "blink" and r.index == 0)
    (word,) = words(client, slave, reg.address)  # 100 = 0064h: bits 2, 5, 6
    for function in (client.read_coils, client.read_discrete_inputs):
        bits = function(reg.address * 16, count=16, device_id=slave).bits[:16]
        assert [int(b) for b in bits] == [(word >> i) & 1 for i in range(16)]
    assert not client.write_coil(reg.address * 16 + 0xD, True, device_id=slave).isError()  # fc 05
    assert words(client, slave, reg.address) == [word | 1 << 0xD]
    reply = client.write_coils(reg.address * 16 + 0xC, [False, False], device_id=slave)  # fc 0F
    assert not reply.isError()
    assert words(client, slave, reg.address) == [word & ~(3 << 0xC)]
    write(client, slave, reg.address, word)
