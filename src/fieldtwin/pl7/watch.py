"""What a compiled program can see, gathered while it is compiled: its idle tasks skipped.

A master task is a function of the objects the program reads and writes.  While the
program is compiled, :class:`WatchedMemory` stands between the compiler and the
memory and notes each object it lends (a cell, a reader, a writer); it also tells
the executor of every Text Block command (a side effect on the PLC).  ``snapshot``
then reads all of those objects at once (one generated function, a tuple).

A task that leaves the snapshot as it found it and starts, resets or faults
nothing is a fixed point: run again on the same snapshot it would do the same
nothing, so the executor may count it without running it (DESIGN rule 3, idle
costs nothing).  Indexed objects (``W10(W0)``) reach a whole table: a program with
one is never skipped.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import itemgetter
from typing import Any

from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import ProgramFault
from fieldtwin.pl7.memory import (
    BitObject,
    Cell,
    IndexedReader,
    IndexedWriter,
    ProgramMemory,
    Reader,
    WordObject,
    Writer,
)

Snapshot = Callable[[], tuple[Any, ...]]


class WatchedMemory:
    """A ProgramMemory that notes what it lends (compile time only)."""

    def __init__(self, memory: ProgramMemory, effect: Callable[[], None]) -> None:
        self.memory = memory
        self.effect = effect
        self.skippable = True
        self._cells: dict[tuple[int, int], tuple[list[int], int]] = {}
        self._readers: dict[object, Reader] = {}  # by the object read (one reader each)

    def _note_cell(self, cell: Cell | None) -> Cell | None:
        if cell is not None:
            table, index, _ = cell
            self._cells.setdefault((id(table), index), (table, index))
        return cell

    def _note_reader(self, obj: BitObject | WordObject, make: Callable[[], Reader]) -> None:
        if obj in self._readers:
            return
        try:
            self._readers[obj] = make()
        except ProgramFault:  # nothing to read back: never skip this program
            self.skippable = False

    # --- ProgramMemory ---------------------------------------------------------------

    def cell(self, obj: BitObject | WordObject) -> Cell | None:
        return self._note_cell(self.memory.cell(obj))

    def read_cell(self, obj: BitObject | WordObject) -> Cell | None:
        read_cell = getattr(self.memory, "read_cell", self.memory.cell)
        cell: Cell | None = read_cell(obj)
        return self._note_cell(cell)

    def bit_reader(self, obj: BitObject) -> Reader:
        reader = self.memory.bit_reader(obj)
        self._readers.setdefault(obj, reader)
        return reader

    def word_reader(self, obj: WordObject) -> Reader:
        reader = self.memory.word_reader(obj)
        self._readers.setdefault(obj, reader)
        return reader

    def bit_writer(self, obj: BitObject) -> Writer:
        writer = self.memory.bit_writer(obj)
        self._note_reader(obj, lambda: self.memory.bit_reader(obj))
        return writer

    def word_writer(self, obj: WordObject) -> Writer:
        writer = self.memory.word_writer(obj)
        self._note_reader(obj, lambda: self.memory.word_reader(obj))
        return writer

    def indexed_reader(self, base: t.Internal) -> IndexedReader:
        self.skippable = False
        return self.memory.indexed_reader(base)

    def indexed_writer(self, base: t.Internal) -> IndexedWriter:
        self.skippable = False
        return self.memory.indexed_writer(base)

    def txt_start(self, index: int, command: str) -> None:
        self.effect()
        self.memory.txt_start(index, command)

    def txt_reset(self, index: int) -> None:
        self.effect()
        self.memory.txt_reset(index)

    def clear_internal(self) -> None:
        self.memory.clear_internal()

    # --- the snapshot ----------------------------------------------------------------

    def snapshot(self, lists: list[list[int]], extra: list[Reader]) -> Snapshot:
        """One function reading every noted object, ``lists`` whole and ``extra``."""
        env: dict[str, Any] = {}
        parts: list[str] = []
        for reader in extra:
            self._readers.setdefault(reader, reader)
        # the cells of one table are read by one itemgetter (a tuple built in C)
        tables: dict[int, tuple[list[int], list[int]]] = {}
        for table, index in self._cells.values():
            tables.setdefault(id(table), (table, []))[1].append(index)
        for k, (table, indexes) in enumerate(tables.values()):
            env[f"_c{k}"] = table
            if len(indexes) == 1:
                parts.append(f"_c{k}[{indexes[0]}]")
            else:
                env[f"_g{k}"] = itemgetter(*indexes)
                parts.append(f"_g{k}(_c{k})")
        for k, reader in enumerate(self._readers.values()):
            env[f"_r{k}"] = reader
            parts.append(f"_r{k}()")
        for k, whole in enumerate(lists):
            env[f"_l{k}"] = whole
            parts.append(f"tuple(_l{k})")
        source = "def _snap():\n    return (" + "".join(p + ", " for p in parts) + ")\n"
        namespace: dict[str, Any] = {}
        exec(compile(source, "<pl7 snapshot>", "exec"), env, namespace)
        snap: Snapshot = namespace["_snap"]
        return snap
