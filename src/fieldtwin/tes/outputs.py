"""Digital outputs: fixed or blinking at two frequencies (§4.1.6), reflex overrides.

The state of a blinking output is computed at read time from the time of
power-on (DESIGN rule 3): no event runs while outputs blink.
"""

from __future__ import annotations

from collections.abc import Callable

from fieldtwin.tes.digital import FILTER_BASE


class DigitalOutputs:
    """``count`` outputs driven by a blink-select mask and a command mask.

    §6.3.2 table: select 0 / command 0 -> 0, select 0 / command 1 -> 1,
    select 1 / command 0 -> blinking frequency 0, select 1 / command 1 -> frequency 1.
    """

    def __init__(self, count: int, blink_word: Callable[[int], int]) -> None:
        self.count = count
        self._blink_word = blink_word  # 0: on 0, 1: off 0, 2: on 1, 3: off 1 (Tb 5 ms)
        self.anchor = 0
        self.blink_select = 0
        self.command = 0
        self.reflex: dict[int, bool] = {}  # §4.2.6 outputs driven by analog thresholds

    def power_on(self, now: int, command: int) -> None:
        self.anchor = now
        self.blink_select = 0
        self.command = command
        self.reflex.clear()

    def _blinking(self, frequency: int, now: int) -> bool:
        on = self._blink_word(2 * frequency) * FILTER_BASE
        off = self._blink_word(2 * frequency + 1) * FILTER_BASE
        if on + off == 0:
            return False
        return (now - self.anchor) % (on + off) < on  # §4.1.6 duration of state 1, then 0

    def commanded(self, i: int, now: int) -> bool:
        """What the master's command gives output ``i`` (ignoring reflex)."""
        bit = (self.command >> i) & 1
        if (self.blink_select >> i) & 1:
            return self._blinking(bit, now)
        return bool(bit)

    def state(self, i: int, now: int) -> bool:
        if i in self.reflex:
            return self.reflex[i]
        return self.commanded(i, now)

    def mask(self, now: int) -> int:
        """All outputs, bit i = output i: the command's fixed bits at once, then each
        blinking output, then the reflex overrides (what ``state`` gives each)."""
        count, command = self.count, self.command
        full = (1 << count) - 1
        blink = self.blink_select & full
        out = command & full & ~blink
        if blink:
            for i in range(count):
                if (blink >> i) & 1 and self._blinking((command >> i) & 1, now):
                    out |= 1 << i
        for i, on in self.reflex.items():
            if 0 <= i < count:
                out = (out | 1 << i) if on else (out & ~(1 << i))
        return out

    def fall_back(self, or_masks: tuple[int, int], and_masks: tuple[int, int]) -> None:
        """AMB-TES-11: command = (command AND and-mask) OR or-mask, for both words."""
        self.blink_select = (self.blink_select & and_masks[0]) | or_masks[0]
        self.command = (self.command & and_masks[1]) | or_masks[1]
