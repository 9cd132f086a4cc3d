"""Reading and writing the words of a TES memory map (§6), by register kind.

``RegisterFile`` is the half of :class:`fieldtwin.tes.model.Tes` that turns a
documented word (a :class:`Register`) into behaviour.  ``peek`` reads without
side effects; ``get`` is a master read (it restores memorized changes, §4.1.2).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from fieldtwin.tes import state
from fieldtwin.tes.analog import AnalogInputs
from fieldtwin.tes.digital import DigitalInputs, Wiring
from fieldtwin.tes.memmap import Register
from fieldtwin.tes.models import Family, TesModel
from fieldtwin.tes.outputs import DigitalOutputs
from fieldtwin.tes.params import Value

_PAIRS = ("counter_rise", "counter_fall", "duration_1", "duration_0", "cumulated_1", "cumulated_0")


class RegisterFile:
    model: TesModel
    params: dict[str, Value]
    words: dict[int, int]  # MP words and other plain RAM words
    di: DigitalInputs
    do: DigitalOutputs
    ai: AnalogInputs
    ao_fallback: int  # bit k: analog output k in fallback (§6.4.4 bit 1)
    status: int
    counters: dict[str, state.LinkCounters]

    # --- reads -------------------------------------------------------------

    def peek(self, reg: Register, now: int) -> int:
        kind, i = reg.kind, reg.index
        if kind in _PAIRS:
            return self._pair(kind, i, now)
        if kind in ("memorized", "filtered", "direct"):
            return self.di.bits(kind, i)
        reader = self._readers().get(kind)
        if reader is not None:
            return reader(i, now) & 0xFFFF
        return self.words.get(reg.address, 0)

    def get(self, reg: Register, now: int) -> int:
        if reg.kind == "memorized":
            self.di.restore_memorized(reg.index)  # AMB-TES-12: shows in this reply
        return self.peek(reg, now)

    def _readers(self) -> Mapping[str, Callable[[int, int], int]]:
        table: Mapping[str, Callable[[int, int], int]] | None = getattr(self, "_reader_table", None)
        if table is None:
            table = self._reader_table = self._make_readers()
        return table

    def _make_readers(self) -> dict[str, Callable[[int, int], int]]:
        return {
            "status": lambda i, now: self.status_word(),
            "zero": lambda i, now: 0,
            "outputs": lambda i, now: self.do.mask(now) >> (16 * i),
            "blink_select": lambda i, now: self.do.blink_select >> (16 * i),
            "command": self._command_word,
            "diag_rs485": lambda i, now: self.counters["rs485"].values[i],
            "diag_rs232": lambda i, now: self.counters["rs232"].values[i],
            "sc": lambda i, now: self._wiring_bits(Wiring.SHORT, i),
            "oc": lambda i, now: self._wiring_bits(Wiring.OPEN, i),
            "fault": lambda i, now: self._wiring_bits(None, i),
            "analog_input": self._analog_input,
            "channel_state": self._channel_state,
            "direct_io": lambda i, now: self.di.bits("direct", 0) | (self.do.mask(now) << 8),
            "history": lambda i, now: self.ai.history(i // 120, i % 120),
        }

    def status_word(self) -> int:
        word = self.status
        if self.model.digital_inputs and self.di.changes_pending:
            word |= state.MEMORIZED  # §6.2.1 bit 3, reset by TES once all are read
        if self.model.is_analog:
            channels = self.ai.channels.values()
            word |= state.LOW_ALARM if any(ch.low for ch in channels) else 0
            word |= state.HIGH_ALARM if any(ch.high for ch in channels) else 0
        return word

    def _command_word(self, i: int, now: int) -> int:
        if self.model.is_analog:  # §6.4.5 blinking choice bits 11-08, states bits 03-00
            return (self.do.blink_select << 8) | self.do.command
        return self.do.command >> (16 * i)

    def _pair(self, kind: str, index: int, now: int) -> int:
        i, low = divmod(index, 2)
        if i >= self.model.digital_inputs:
            return 0  # AMB-TES-13: inputs the model does not have read 0
        value = self.di.value32(kind, i, now)
        return value & 0xFFFF if low else value >> 16

    def _wiring_bits(self, wiring: Wiring | None, word: int) -> int:
        """§6.2.7 SC / OC / default words; only inputs wired in security mode report."""
        connection = self.words.get(0x1AB + word, 0)
        out = 0
        for bit in range(16):
            i = 16 * word + bit  # AMB-TES-23: bit 0 = E1 = input No 0
            w = self.di.wiring(i)
            if (connection >> bit) & 1 and w is not Wiring.OK and wiring in (None, w):
                out |= 1 << bit
        return out

    def safety_default(self) -> bool:
        return any(self._wiring_bits(None, w) for w in (0, 1))

    def _analog_input(self, k: int, now: int) -> int:
        ch = self.ai.channels.get(k)
        return 0 if ch is None else ch.value & 0xFFFF

    def _channel_state(self, k: int, now: int) -> int:
        word = 0x02 if (self.ao_fallback >> k) & 1 else 0  # §6.4.4 bit 1
        ch = self.ai.channels.get(k)
        if ch is not None:
            word |= (0x10 if ch.low else 0) | (0x20 if ch.high else 0)  # bits 4 / 5
        return word

    # --- writes ------------------------------------------------------------

    def put(self, reg: Register, value: int, now: int) -> None:
        """A master write of an already checked writable word."""
        kind, i = reg.kind, reg.index
        if kind in _PAIRS:
            self._put_pair(kind, i, value, now)
        elif kind == "status":
            self.status &= value | ~state.MASTER_RESETS[self.model.family]
        elif kind == "blink_select":
            self.do.blink_select = _splice(self.do.blink_select, i, value)
        elif kind == "command":
            self._put_command(i, value)
        elif kind in ("diag_rs485", "diag_rs232"):
            self.counters[kind[5:]].values[i] = value
        elif kind == "analog_output":
            self.words[reg.address] = value
            self.ao_fallback &= ~(1 << i)  # a fresh command ends the fallback position
        else:
            self.words[reg.address] = value
            self.after_parameter_write(kind, now)

    def _put_command(self, i: int, value: int) -> None:
        if self.model.is_analog:
            self.do.blink_select, self.do.command = (value >> 8) & 0xF, value & 0xF
        else:
            self.do.command = _splice(self.do.command, i, value)
        if self.model.family is Family.DIGITAL_INPUTS:
            self.words[0x00D] = self.do.command & 0xFFFF

    def _put_pair(self, kind: str, index: int, value: int, now: int) -> None:
        i, low = divmod(index, 2)
        if i >= self.model.digital_inputs:
            return
        old = self.di.value32(kind, i, now)
        new = (old & 0xFFFF0000) | value if low else (value << 16) | (old & 0xFFFF)
        self.di.set_value32(kind, i, new, now)

    def after_parameter_write(self, kind: str, now: int) -> None:
        raise NotImplementedError


def _splice(mask: int, word: int, value: int) -> int:
    """Replace 16-bit word ``word`` of a 32-bit mask."""
    shift = 16 * word
    return (mask & ~(0xFFFF << shift)) | (value << shift)
