"""Master watching and the fallback position (§3.1.3, §4.1.7, §6.2.3.1, §6.4.11).

``MasterWatch`` re-arms a timer at each request on RS-485 (AMB-TES-10) and,
when it runs out, puts the outputs in their fallback position, sets status
bit 1 and makes the Wdg LED blink until the master asks again.
"""

from __future__ import annotations

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.modbus.model import Link
from fieldtwin.tes import state
from fieldtwin.tes.models import Family, TesModel
from fieldtwin.tes.outputs import DigitalOutputs

WATCHDOG_BASE = 100 * MS  # §6.2.3.1 Tb = 100 ms


class MasterWatch:
    """The master-watching timer of one TES and what its end does."""

    def __init__(
        self, model: TesModel, clock: SimClock, ram: state.Ram, do: DigitalOutputs
    ) -> None:
        self.model = model
        self._clock = clock
        self._ram = ram
        self._do = do
        self._address = 0x03C if model.is_analog else 0x016
        self._handle: Handle | None = None

    def arm(self, now: int) -> None:
        self.stop()
        period = self._ram.word(self._address) * WATCHDOG_BASE
        if period and self._ram.powered:
            self._handle = self._clock.schedule(now + period, self._fall_back)

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def master_request(self, link: Link, now: int) -> None:
        """AMB-TES-10: a request to this slave (or broadcast) on RS-485 re-arms the watchdog."""
        ram = self._ram
        ram.wdg_blinking = False
        # arm(now) with no timer running and no watching time does nothing: not called
        if link is not Link.RS232 and (self._handle is not None or ram.words.get(self._address)):
            self.arm(now)

    def _fall_back(self, now: int) -> None:
        self._handle = None
        ram = self._ram
        ram.status |= state.FALLBACK
        ram.wdg_blinking = True  # §3.1.3 "led Wdg will blinking"
        if self.model.is_analog:
            self._analog_fall_back()
            return
        w = ram.words
        if self.model.family is Family.DIGITAL_OUTPUTS:
            or_ = (w[0x00E] | w[0x00F] << 16, w[0x010] | w[0x011] << 16)
            and_ = (w[0x012] | w[0x013] << 16, w[0x014] | w[0x015] << 16)
        else:
            or_, and_ = (w[0x012], w[0x013]), (w[0x014], w[0x015])
        self._do.fall_back(or_, and_)
        if self.model.family is Family.DIGITAL_INPUTS:
            w[0x00D] = self._do.command & 0xFFFF

    def _analog_fall_back(self) -> None:
        # §6.4.11.2 same layout as the command word; reflex outputs do not fall back
        ram, do = self._ram, self._do
        command = ram.words[0x03D]
        do.blink_select, do.command = (command >> 8) & 0xF, command & 0xF
        enable = ram.words[0x046]
        for k in self.model.analog_outputs:  # §6.4.11.3 authorised outputs only
            if (enable >> k) & 1:
                ram.words[0x014 + k] = ram.words[0x03E + k]
                ram.ao_fallback |= 1 << k
