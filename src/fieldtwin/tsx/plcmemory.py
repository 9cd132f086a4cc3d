"""The PLC's objects as a PL7-3 program sees them: ``fieldtwin.pl7.ProgramMemory``.

Internal bits B, internal words W (the Text Blocks' tables, ``TextBlocks.data``),
constant words CW, system bits SY and words SW are lists of the PLC; module objects
are the PLC's bus images (inputs as read at the end of the previous master task,
outputs written to the modules at the end of this one); Text Block fields are the
PLC's TextBlocks (inputs M, C, L kept here; outputs D, E, V/R, S from the block).

A Text Block is declared as the programming terminal declares it (AEM 3.5-1 "The
above data must be entered by using the terminal in Configuration mode"):
``TxtDeclaration(indirect=20)`` is the AEM 5.1 "CPL INDIRECT W20" (the addressing
table W20..W25: transmission table type, address, length in bytes; reception type,
address, length; type 0 = W, 1 = CW, docs/manual-notes.md), or a direct
declaration ``TxtDeclaration(send=("W", 1130), recv=("W", 1000))``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from fieldtwin.errors import ConfigError
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import ProgramFault
from fieldtwin.pl7.memory import BitObject, Cell, IndexedReader, IndexedWriter, Reader, Writer
from fieldtwin.tsx.addressing import ObjectKind, ObjectRef
from fieldtwin.tsx.slots import PlcModel, Slot
from fieldtwin.tsx.txt import DATA_WORDS, TextBlock, TextBlocks, TxtState
from fieldtwin.words import words_to_bytes


class Plc(Protocol):
    """What the program memory reads and writes of the PLC (fieldtwin.tsx.plc.Plc)."""

    model: PlcModel
    txt: TextBlocks
    data: list[int]
    bits: list[int]
    cw: list[int]
    sy: list[int]
    sw: list[int]

    def slot_entry(self, rack: int, slot: int) -> Slot: ...

    def reset_text_block(self, txt: int) -> None: ...


SYSTEM_BITS = 128
SYSTEM_WORDS = 128
INTERNAL_BITS = 4096
CONSTANT_WORDS = 4096
_INPUTS = (ObjectKind.IW, ObjectKind.I, ObjectKind.FAULT)
TABLE_TYPES = {0: "W", 1: "CW"}  # addressing-table type words (our reading, manual-notes)


@dataclass(frozen=True, slots=True)
class TxtDeclaration:
    """How a Text Block's tables are declared (configuration mode, not program)."""

    indirect: int | None = None  # Wi: the addressing table Wi..Wi+5
    send: tuple[str, int] | None = None  # ("W" or "CW", address)
    recv: tuple[str, int] | None = None  # ("W", address)
    send_words: int | None = None  # the declared transmission table length, W200 (4)


class PlcMemory:
    """ProgramMemory over a Plc."""

    def __init__(self, plc: Plc) -> None:
        self.plc = plc
        self.inputs: dict[int, dict[str, int]] = {}
        self.declarations: dict[int, TxtDeclaration] = {}

    def _table(self, kind: str) -> list[int]:
        plc = self.plc
        tables = {"B": plc.bits, "W": plc.data, "CW": plc.cw, "SY": plc.sy, "SW": plc.sw}
        return tables[kind]

    # --- cells, readers, writers ----------------------------------------------------

    def cell(self, obj: BitObject | t.Internal | t.ModuleObj | t.TxtField) -> Cell | None:
        if isinstance(obj, t.Internal):
            return self._table(obj.kind), obj.index, None
        if isinstance(obj, t.InternalBit):
            return self._table(obj.word.kind), obj.word.index, obj.bit
        if isinstance(obj, t.ModuleObj) and obj.ref.kind is ObjectKind.OW:
            entry = self.plc.slot_entry(obj.ref.rack, obj.ref.slot)
            return entry.ow, obj.ref.index or 0, obj.ref.bit
        if isinstance(obj, t.ModuleObj) and obj.ref.kind is ObjectKind.O:
            entry = self.plc.slot_entry(obj.ref.rack, obj.ref.slot)
            return entry.outputs, 0, obj.ref.index or 0
        return None

    def read_cell(self, obj: BitObject | t.Internal | t.ModuleObj | t.TxtField) -> Cell | None:
        """``cell``, and the input images too (read in place by the compiled program;
        never written: ``cell`` gives no input, so a store to one is refused)."""
        if isinstance(obj, t.ModuleObj) and obj.ref.kind in _INPUTS:
            ref = obj.ref
            entry = self.plc.slot_entry(ref.rack, ref.slot)
            if ref.kind is ObjectKind.IW:
                return entry.words, ref.index or 0, ref.bit
            if ref.kind is ObjectKind.I:
                return entry.inputs, 0, ref.index or 0
            return entry.inputs, 1, None  # Ixy,S
        return self.cell(obj)

    def bit_reader(self, obj: BitObject) -> Reader:
        if isinstance(obj, t.TxtField):
            return self._txt_reader(obj)
        if isinstance(obj, t.ModuleObj):
            return self._module_reader(obj.ref)
        cell = self.cell(obj)
        assert cell is not None
        table, i, bit = cell
        if bit is None:
            return lambda: table[i]
        b = bit
        return lambda: (table[i] >> b) & 1

    def bit_writer(self, obj: BitObject) -> Writer:
        if isinstance(obj, t.TxtField):
            raise ProgramFault(f"TXT{obj.index},{obj.name} is an output of the Text Block")
        if isinstance(obj, t.ModuleObj) and obj.ref.kind is ObjectKind.O:
            entry = self.plc.slot_entry(obj.ref.rack, obj.ref.slot)
            mask = 1 << (obj.ref.index or 0)

            def write_o(value: int) -> None:
                entry.o_bits = (entry.o_bits | mask) if value else (entry.o_bits & ~mask)

            return write_o
        cell = self.cell(obj)
        if cell is None:
            raise ProgramFault(f"{obj} cannot be written")
        table, i, bit = cell
        if bit is None:

            def write(value: int) -> None:
                table[i] = value

            return write
        m = 1 << bit

        def write_bit(value: int) -> None:
            table[i] = (table[i] | m) if value else (table[i] & ~m)

        return write_bit

    def word_reader(self, obj: t.Internal | t.ModuleObj | t.TxtField) -> Reader:
        return self.bit_reader(obj)

    def word_writer(self, obj: t.Internal | t.ModuleObj | t.TxtField) -> Writer:
        if isinstance(obj, t.TxtField):
            fields, name = self._txt_inputs(obj.index), obj.name
            if name not in fields:
                raise ProgramFault(f"TXT{obj.index},{name} is an output of the Text Block")

            def write_field(value: int) -> None:
                fields[name] = value

            return write_field
        return self.bit_writer(obj)

    def indexed_reader(self, base: t.Internal) -> IndexedReader:
        table, start = self._table(base.kind), base.index

        def read(offset: int) -> int:
            at = start + offset
            if at >= len(table):
                raise ProgramFault(f"{base.kind}{start}({offset}): {base.kind}{at} past the table")
            return table[at]

        return read

    def indexed_writer(self, base: t.Internal) -> IndexedWriter:
        table, start = self._table(base.kind), base.index

        def write(offset: int, value: int) -> None:
            at = start + offset
            if at >= len(table):
                raise ProgramFault(f"{base.kind}{start}({offset}): {base.kind}{at} past the table")
            table[at] = value

        return write

    # --- modules ----------------------------------------------------------------------

    def _module_reader(self, ref: ObjectRef) -> Reader:
        entry = self.plc.slot_entry(ref.rack, ref.slot)
        i = ref.index or 0
        if ref.kind is ObjectKind.FAULT:
            return lambda: int(entry.image.fault)
        if ref.kind is ObjectKind.I:
            return lambda: (entry.image.i_bits >> i) & 1
        if ref.kind is ObjectKind.O:
            return lambda: (entry.o_bits >> i) & 1
        if ref.kind is ObjectKind.IW:
            if ref.bit is None:
                return lambda: entry.image.iw[i]
            b = ref.bit
            return lambda: (entry.image.iw[i] >> b) & 1
        ow, b2 = entry.ow, ref.bit
        if b2 is None:
            return lambda: ow[i]
        return lambda: (ow[i] >> b2) & 1

    # --- Text Blocks --------------------------------------------------------------------

    def _txt_inputs(self, index: int) -> dict[str, int]:
        return self.inputs.setdefault(index, {"M": 0, "C": 0, "L": 0})

    def _txt_reader(self, obj: t.TxtField) -> Reader:
        if obj.name in ("M", "C", "L"):
            fields, name = self._txt_inputs(obj.index), obj.name
            return lambda: fields[name]
        tb = self.plc.txt.block(obj.index)
        if obj.name == "D":  # 1 before the first exchange (SCM 4.6 SR7 starts on TXT0,D)
            machine, done = tb.machine, (TxtState.IDLE, TxtState.DONE)  # a block keeps its
            return lambda: int(machine.state in done)  # machine: tb.state is machine.state
        if obj.name == "E":
            return lambda: int(tb.result is not None and tb.result.e)
        if obj.name == "S":
            return lambda: 0 if tb.result is None else tb.result.s
        return lambda: 0 if tb.result is None else tb.result.v  # V, R

    def txt_start(self, index: int, command: str) -> None:
        plc, fields = self.plc, self._txt_inputs(index)
        tb: TextBlock = plc.txt.block(index)
        if tb.state in (TxtState.STARTED, TxtState.IN_MODULE, TxtState.ANSWERED):
            raise ProgramFault(f"{command} TXT{index}: its exchange is still in progress")
        declared = self.declarations.get(index, TxtDeclaration())
        send: list[int] = []
        length = fields["L"]
        recv_table: int | None = None
        capacity = plc.model.table_max if command != "OUTPUT" else 0
        if declared.indirect is not None:
            a = declared.indirect
            words = plc.data[a : a + 6]
            if len(words) < 6 or words[0] not in TABLE_TYPES or words[3] not in TABLE_TYPES:
                raise ProgramFault(f"{command} TXT{index}: incorrect addressing table W{a}")
            source = self._table(TABLE_TYPES[words[0]])
            length = words[2]
            send = source[words[1] : words[1] + (length + 1) // 2]
            recv_table, capacity = words[4], words[5]
        else:
            if declared.send is not None:
                kind, at = declared.send
                if length == 0 and declared.send_words is not None:  # the whole table
                    length = 2 * declared.send_words
                send = self._table(kind)[at : at + (length + 1) // 2]
            if declared.recv is not None:
                recv_table = declared.recv[1]
        data = words_to_bytes(send)[:length] if command != "INPUT" else b""
        if recv_table is not None and recv_table >= DATA_WORDS:
            raise ProgramFault(f"{command} TXT{index}: reception table W{recv_table} past W4095")
        try:
            plc.txt.start(
                fields["M"],
                fields["C"],
                send_bytes=data,
                recv_bytes=capacity,
                txt=index,
                recv_table=recv_table,
            )
        except ConfigError as err:
            raise ProgramFault(str(err)) from None

    def txt_reset(self, index: int) -> None:
        self.plc.reset_text_block(index)

    def clear_internal(self) -> None:
        plc = self.plc
        plc.bits[:] = [0] * len(plc.bits)
        plc.data[:] = [0] * len(plc.data)


# --- the calendar of the system words SW51..SW56 (sans-IO: no datetime) --------------


def civil_from_days(days: int) -> tuple[int, int, int]:
    """Days since 1970-01-01 -> (year, month, day), proleptic Gregorian."""
    z = days + 719468
    era = (z if z >= 0 else z - 146096) // 146097
    doe = z - era * 146097
    yoe = (doe - doe // 1460 + doe // 36524 - doe // 146096) // 365
    doy = doe - (365 * yoe + yoe // 4 - yoe // 100)
    mp = (5 * doy + 2) // 153
    day = doy - (153 * mp + 2) // 5 + 1
    month = mp + 3 if mp < 10 else mp - 9
    return yoe + era * 400 + (month <= 2), month, day


def days_from_civil(year: int, month: int, day: int) -> int:
    y = year - (month <= 2)
    era = (y if y >= 0 else y - 399) // 400
    yoe = y - era * 400
    doy = (153 * (month + (-3 if month > 2 else 9)) + 2) // 5 + day - 1
    doe = yoe * 365 + yoe // 4 - yoe // 100 + doy
    return era * 146097 + doe - 719468


def calendar_words(epoch_s: int) -> dict[int, int]:
    """SW51 seconds, SW52 minutes, SW53 hours, SW54 day, SW55 month, SW56 year (the
    DEM 5.3-4 POST L12 reads them so; docs/manual-notes.md)."""
    days, rest = divmod(epoch_s, 86400)
    year, month, day = civil_from_days(days)
    return {51: rest % 60, 52: rest // 60 % 60, 53: rest // 3600, 54: day, 55: month, 56: year}
