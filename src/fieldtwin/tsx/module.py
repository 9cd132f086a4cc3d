"""What every TSX Series 7 intelligent module shares.

The full I/O bus interface (AEM 1.1-1, 2.4): 16 discrete input bits and the
fault bit Ixy,S, discrete outputs where a module has them, 8 input and 8 output
register words, and the message interface (Text Blocks).  The operating modes
(AEM 2.5): initial self-test, Run/Stop following OWxy,0,C, awaiting
configuration, the message-system reset OWxy,0,2.  Fault processing (AEM 4.4-1):
bits IWxy,0,4/6/7 memorised until the fault bit string is read, IWxy,0,8 and
IWxy,0,A live, the LEDs OK / ERR / F.  The requests every module shares
(AEM 4.4-2, SCM 6.3): H'0F' version, H'49'/H'4A' application name, H'47' fault
bit string.

A module is a sans-IO core: it never sleeps or reads a clock; time comes from
the SimClock it is given, and the PLC drives the bus by calling
:meth:`IntelligentModule.bus_write` / :meth:`IntelligentModule.bus_read`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar, cast

from fieldtwin.clock import Handle as ClockHandle
from fieldtwin.clock import S
from fieldtwin.errors import ConfigError, ProtocolError
from fieldtwin.fsm import Machine, Table
from fieldtwin.hosting import host
from fieldtwin.tsx.bus import BusImage, LedState, ModuleContext, ModuleEvent, ModuleState
from fieldtwin.tsx.faults import FaultCategory, FaultLatches
from fieldtwin.tsx.messages import Exchanges, OnDone
from fieldtwin.tsx.textblock import (
    ERR_MODULE_FAULT,
    ERR_POWER_BREAK,
    V_ERROR,
    Answer,
    Exchange,
    Request,
)
from fieldtwin.words import get_bit

# IWxy,0 standard status word (AEM 4.4-1 and the quick reference)
ST_RESET_DONE = 0x2  # ongoing exchange cancelled, follows OWxy,0,2
ST_READY = 0x3  # module available: self-test complete
ST_GENERAL_FAULT = 0x4  # memorised: OR of bits 6 and 7
ST_MODULE_FAULT = 0x6  # memorised: acquisition/conversion (module) fault
ST_APPLICATION_FAULT = 0x7  # memorised: application fault (sensors, wiring)
ST_BLOCKING_FAULT = 0x8  # blocking fault (module failure)
ST_SELF_TEST = 0x9  # initial self-test in progress
ST_TERMINAL_BLOCK = 0xA  # terminal block open or not fitted
ST_AWAITING_CONFIG = 0xB  # waiting for a configuration
ST_RUN = 0xC  # module Run (0 = Stop)

# OWxy,0 standard command word
CMD_RESET_EXCHANGE = 0x2  # message-system reset
CMD_RUN = 0xC  # module Run/Stop

PRUNE_MIN = 32  # handles kept before the fired ones are dropped from the list
BusListener = Callable[["IntelligentModule"], None]


class InputWords(list[int]):
    """IWxy,0..7 as the module writes them: a list that tells its module of every
    write, so that the PLC reads the bus face of a module only after it changed
    (DESIGN rule 3: an idle module costs nothing at the bus refresh)."""

    __slots__ = ("_changed",)

    def __init__(self, values: list[int], changed: Callable[[], None]) -> None:
        super().__init__(values)
        self._changed = changed

    def __setitem__(self, key: Any, value: Any) -> None:
        list.__setitem__(self, key, value)
        self._changed()


class IntelligentModule:
    """Base of every intelligent module twin; subclasses add their function."""

    type_name: ClassVar[str] = "intelligent module"
    # Codes a slot may be declared with (hardware code on TSX 47-30/67/87, software
    # code on a TSX 47-20); another code sets Ixy,S (AEM 4.4-1).
    hardware_codes: ClassVar[frozenset[int]] = frozenset()
    software_codes: ClassVar[frozenset[int]] = frozenset()
    self_test_us: ClassVar[int] = 10 * S
    fault_string_bytes: ClassVar[int] = 8
    version_text: ClassVar[str] = "INTELLIGENT MODULE V1.0"
    has_run_stop: ClassVar[bool] = True  # OWxy,0,C drives IWxy,0,C
    discrete_outputs: ClassVar[int] = 0  # Oxy,0.. a module has
    # Which bit rows of the slot a front shows: Ixy,i (the module's I bits) and Oxy,i
    # (the PLC's O bits); a discrete input module has no O bits, an output module no I bits
    shows_i_bits: ClassVar[bool] = True
    shows_o_bits: ClassVar[bool] = True
    # which terminal-block fault bit of the fault string drives IWxy,0,A (None: none)
    terminal_block_fault_bit: ClassVar[int | None] = None
    # The LEDs of the front panel, as printed on it (AEM 4.4-1 "F", "OK", "ERR")
    led_names: ClassVar[tuple[str, ...]] = ("OK", "ERR", "F")
    # At most N modules of this group in one PLC configuration: (group name, N)
    plc_limit: ClassVar[tuple[str, int] | None] = None

    def __init__(
        self, ctx: ModuleContext, rack: int, slot: int, *, declared_code: int | None = None
    ) -> None:
        self.ctx = ctx
        self.clock = ctx.clock
        self.rack = rack
        self.slot = slot
        self.declared_code = declared_code
        self._mode: Machine[ModuleState, ModuleEvent, IntelligentModule] = Machine(
            MODES, ModuleState.OFF, self
        )
        # The bus face (IWxy,i, Ixy,i, Ixy,S) changed since the PLC last read it: set
        # by every write of iw or i_bits, every change of mode or fault; the PLC's
        # listener is told once, when the flag goes up (Plc.insert sets it).
        self.bus_dirty = True
        self.bus_listener: BusListener | None = None
        self._iw = InputWords([0] * 8, self.bus_changed)  # written by the module
        self._i_bits = 0
        self.ow = [0] * 8  # written by the PLC
        self.o_bits = 0
        self.awaiting_configuration = False
        self.app_name = b""
        self._faults = FaultLatches(self.bus_changed)
        self.exchanges = Exchanges(self)  # the message interface (AEM 2.4-4)
        self._handles: list[ClockHandle] = []  # what a power-off cancels
        self._prune_at = PRUNE_MIN
        self._self_test: ClockHandle | None = None
        self._hardware_faults: set[int] = set()  # found by the next initial self-test

    # --- the bus face: what the PLC reads --------------------------------------

    @property
    def iw(self) -> list[int]:
        """The input words IWxy,0..7 (the PLC reads them at its bus refresh)."""
        return self._iw

    @iw.setter
    def iw(self, values: list[int]) -> None:
        self._iw = InputWords(list(values), self.bus_changed)
        self.bus_changed()

    @property
    def i_bits(self) -> int:
        """The discrete input bits Ixy,0..F."""
        return self._i_bits

    @i_bits.setter
    def i_bits(self, value: int) -> None:
        if value != self._i_bits:
            self._i_bits = value
            self.bus_changed()

    def bus_changed(self) -> None:
        """Something the PLC reads may have changed: it reads this module again."""
        if not self.bus_dirty:
            self.bus_dirty = True
            listener = self.bus_listener
            if listener is not None:
                listener(self)

    # --- identity ---------------------------------------------------------

    @property
    def address(self) -> str:
        return f"{self.slot}" if self.rack == 0 else f"{self.rack}{self.slot}"

    @property
    def code_ok(self) -> bool:
        if self.declared_code is None:
            return True
        codes = self.software_codes if self.ctx.plc_model == "TSX 47-20" else self.hardware_codes
        return not codes or self.declared_code in codes

    # --- scheduling that power-off cancels -------------------------------

    def call_later(self, delay: int, callback: Callable[[int], None]) -> ClockHandle:
        return self.call_at(self.clock.now + delay, callback)

    def call_at(self, at: int, callback: Callable[[int], None]) -> ClockHandle:
        if at < self.clock.now:
            raise ConfigError(f"delay must be >= 0 us, got {at - self.clock.now}")
        handle = self.clock.schedule(at, callback)
        handles = self._handles
        handles.append(handle)
        if len(handles) > self._prune_at:  # fired and cancelled handles go, in bulk
            self._handles = handles = [h for h in handles if h.active]
            self._prune_at = max(PRUNE_MIN, 2 * len(handles))
        return handle

    def call_at_as(self, at: int, seq: int, callback: Callable[[int], None]) -> ClockHandle:
        """``call_at`` with a sequence number reserved earlier (``SimClock.reserve``)."""
        handle = self.clock.schedule_as(at, seq, callback)
        handles = self._handles
        handles.append(handle)
        if len(handles) > self._prune_at:
            self._handles = handles = [h for h in handles if h.active]
            self._prune_at = max(PRUNE_MIN, 2 * len(handles))
        return handle

    # --- the operating-mode machine (DESIGN rule 4: the MODES table below) --

    @property
    def state(self) -> ModuleState:
        """The operating mode: off, self-test, operational (Run or Stop) or blocked."""
        return self._mode.state

    def _fire(self, event: ModuleEvent, now: int) -> None:
        if not self._mode.can(event):
            raise ProtocolError(
                f"{self.type_name} in slot {self.address}: can't handle {event.value!r}"
                f" in state {self.state.value}"
            )
        self._mode.fire(event, now)
        self.bus_changed()
        self.refresh_status()

    def power_on(self, now: int | None = None) -> None:
        """Power-up, power return after a long break, or insertion under power."""
        self._fire(ModuleEvent.POWER_ON, self.clock.now if now is None else now)

    def power_off(self, now: int | None = None) -> None:
        """Power removed, or module pulled out of its slot."""
        self._fire(ModuleEvent.POWER_OFF, self.clock.now if now is None else now)

    def _start_self_test(self, now: int) -> None:
        # AEM 7.1-1: ERR and OK lit, IWxy,0,9 = 1, measurements not valid
        self.iw = [0] * 8
        self.i_bits = 0
        self._faults.clear()
        self.awaiting_configuration = False
        self.on_power_on(now)
        self._self_test = self.call_later(self.self_test_us, self._self_test_over)

    def _self_test_over(self, now: int) -> None:
        if any(
            self._fault_category(bit) is FaultCategory.BLOCKING for bit in self._hardware_faults
        ):
            for bit in self._hardware_faults:
                self._set_latch(bit, True, self._fault_category(bit))
            self._fire(ModuleEvent.BLOCKING_FAULT, now)
            return
        self._fire(ModuleEvent.SELF_TEST_DONE, now)

    def _end_self_test(self, now: int) -> None:
        # Faults found by the initial self-test (AEM 7.1-1) are raised now.
        for bit in sorted(self._hardware_faults):
            self._set_latch(bit, True, self._fault_category(bit))
        self.on_self_test_done(now)
        self.exchanges.dispatch_held(now)

    def _block(self, now: int) -> None:
        if self._self_test is not None:  # AEM 7.1-1: a blocked module never becomes ready
            self._self_test.cancel()
        # SCM 6.4: a blocking fault "stops the user program from accessing the module
        # through the Text block": what the module held ends as a module fault.
        self.exchanges.end_all(Answer.fault(ERR_MODULE_FAULT), now)
        self.on_blocked(now)

    def _power_down(self, now: int) -> None:
        for handle in self._handles:
            handle.cancel()
        self._handles.clear()
        self.exchanges.end_all(Answer.fault(ERR_POWER_BREAK), now)
        self.exchanges.clear()
        self.iw = [0] * 8
        self.i_bits = 0
        # an unpowered module holds no outputs: the first refresh after power return
        # delivers the PLC's output image again (bus_write only passes changes on)
        self.ow = [0] * 8
        self.o_bits = 0
        self.on_power_off(now)

    # --- hooks for subclasses ---------------------------------------------

    def on_power_on(self, now: int) -> None:
        """Power-up: reset volatile state (configuration lost on most modules)."""

    def on_self_test_done(self, now: int) -> None:
        """Self-test passed: start the function (default configuration...)."""

    def on_power_off(self, now: int) -> None:
        """Power gone: every scheduled event is already cancelled."""

    def on_blocked(self, now: int) -> None:
        """A blocking fault took the module out of service."""

    def on_run_changed(self, running: bool, now: int) -> None:
        """IWxy,0,C changed."""

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        """The PLC wrote new output words/bits (self.ow, self.o_bits)."""

    def run_permitted(self) -> bool:
        """Beyond OWxy,0,C: may the module run (configuration valid...)?"""
        return not self.awaiting_configuration

    def handle_request(self, exchange: Exchange, now: int) -> None:
        """A request the base does not know: answer it with ``exchange.complete``."""
        exchange.complete(Answer(v=V_ERROR), now)

    # --- run / stop --------------------------------------------------------

    @property
    def running(self) -> bool:
        return bool(self._iw[0] >> ST_RUN & 1)

    def _compute_run(self) -> bool:
        if self.state is not ModuleState.OPERATIONAL or not self.code_ok:
            return False
        if not self.has_run_stop:
            return False
        if self._faults.any(FaultCategory.MODULE, memorised=False):
            return False  # AEM 2.5-4: module to Stop until the fault disappears
        return bool(self.ow[0] >> CMD_RUN & 1) and self.run_permitted()

    # --- faults (AEM 4.4-1) ------------------------------------------------

    def _fault_category(self, bit: int) -> FaultCategory:
        return self._faults.category(bit) or self.fault_category_of(bit)

    def fault_category_of(self, bit: int) -> FaultCategory:
        """Category of fault-string bit ``bit`` (subclasses map their layout)."""
        return FaultCategory.APPLICATION

    def set_fault(self, bit: int, active: bool, category: FaultCategory | None = None) -> None:
        """Raise or clear fault ``bit`` of the fault bit string."""
        if not 0 <= bit < 8 * self.fault_string_bytes:
            raise ConfigError(
                f"fault bit {bit} out of range (allowed 0..{8 * self.fault_string_bytes - 1})"
            )
        cat = category or self._fault_category(bit)
        if self.state is ModuleState.OFF:
            return
        if cat is FaultCategory.BLOCKING and active:
            self._set_latch(bit, True, cat)
            if self.state is not ModuleState.BLOCKED:
                self._fire(ModuleEvent.BLOCKING_FAULT, self.clock.now)
            return
        self._set_latch(bit, active, cat)
        self.refresh_status()

    def _set_latch(self, bit: int, active: bool, category: FaultCategory) -> None:
        self._faults.set(bit, active, category)

    def fault_active(self, bit: int) -> bool:
        return self._faults.active(bit)

    def hardware_fault(self, bit: int, present: bool = True) -> None:
        """A fault the next initial self-test will find (and, powered, now)."""
        if present:
            self._hardware_faults.add(bit)
        else:
            self._hardware_faults.discard(bit)
        if self.state is not ModuleState.OFF:
            self.set_fault(bit, present)

    def read_fault_string(self) -> bytes:
        """The fault bit string; reading it acknowledges the memorised bits."""
        data = self._faults.read(self.fault_string_bytes)
        self.refresh_status()
        return data

    def _any(self, category: FaultCategory, *, memorised: bool) -> bool:
        return self._faults.any(category, memorised=memorised)

    @property
    def module_fault(self) -> bool:
        """Ixy,S: blocking or module fault, wrong declared code (AEM 4.4-1)."""
        state = self._mode.state
        if state is ModuleState.OFF or state is ModuleState.BLOCKED:
            return True
        if self.declared_code is not None and not self.code_ok:
            return True
        return self._any(FaultCategory.MODULE, memorised=False)

    @property
    def leds(self) -> dict[str, LedState]:
        """The front-panel LEDs, by the name printed on the panel: "on", "off" or
        "blink"; only the LEDs this module's front panel has (``led_names``)."""
        states = self.led_states()
        return {name: states.get(name, "off") for name in self.led_names}

    def led_states(self) -> dict[str, LedState]:
        """OK / ERR / F (AEM 4.4-1 and 7.1-1, DEM 4.3); a subclass may add its own."""
        if self.state is ModuleState.OFF:
            return _lit()
        if self.state is ModuleState.SELF_TEST:
            return _lit("OK", "ERR")
        if self.state is ModuleState.BLOCKED:
            return _lit("F")
        ok = not self._any(FaultCategory.MODULE, memorised=False)
        err = self._any(FaultCategory.APPLICATION, memorised=False)
        return _lit(*(["OK"] if ok else []), *(["ERR"] if err else []))

    @property
    def led_text(self) -> str:
        """The LEDs on one line: ``OK=on ERR=off F=off``."""
        return " ".join(f"{name}={state}" for name, state in self.leds.items())

    # --- status word ---------------------------------------------------------

    def standard_status(self) -> int:
        word = self.iw[0] & ~0x1FFC & 0xFFFF  # keep bits a subclass owns (0, 1, D..F)
        state = self._mode.state
        if state is ModuleState.OFF:
            return 0
        module = self._any(FaultCategory.MODULE, memorised=True)
        application = self._any(FaultCategory.APPLICATION, memorised=True)
        # bits 2..C are clear in ``word``: each is OR-ed in once
        word |= ((self.ow[0] >> CMD_RESET_EXCHANGE) & 1) << ST_RESET_DONE
        word |= (state is ModuleState.OPERATIONAL) << ST_READY
        word |= bool(module) << ST_MODULE_FAULT
        word |= bool(application) << ST_APPLICATION_FAULT
        word |= bool(module or application) << ST_GENERAL_FAULT
        # AEM 4.4-1: "Blocking fault, or module absent or incorrectly coded"
        blocked = state is ModuleState.BLOCKED or not self.code_ok
        word |= blocked << ST_BLOCKING_FAULT
        word |= (state is ModuleState.SELF_TEST) << ST_SELF_TEST
        tb = self.terminal_block_fault_bit
        word |= (tb is not None and self.fault_active(tb)) << ST_TERMINAL_BLOCK
        word |= bool(self.awaiting_configuration) << ST_AWAITING_CONFIG
        return word | bool(self._compute_run()) << ST_RUN

    def refresh_status(self) -> None:
        """Recompute IWxy,0; call after anything that may change it."""
        if self.state is ModuleState.OFF:
            self.iw[0] = 0
            return
        was_running = self.running
        word = self.standard_status()
        if self._iw[0] != word:  # an unchanged word is not written: no new bus read
            self._iw[0] = word
        if self.running != was_running:
            self.on_run_changed(self.running, self.clock.now)

    # --- the bus -------------------------------------------------------------

    def bus_write(self, ow: list[int], o_bits: int, now: int) -> None:
        """The PLC refreshes the output words and bits."""
        if self.state is ModuleState.OFF or (ow == self.ow and o_bits == self.o_bits):
            return  # nothing new on the bus: an idle module costs nothing more
        old_ow, old_o = self.ow, self.o_bits
        self.ow, self.o_bits = list(ow), o_bits
        if not get_bit(old_ow[0], CMD_RESET_EXCHANGE) and get_bit(ow[0], CMD_RESET_EXCHANGE):
            self.reset_exchanges(now)  # message-system reset, rising edge
        self.on_outputs(old_ow, old_o, now)
        self.refresh_status()

    def bus_read(self) -> BusImage:
        return BusImage(tuple(self._iw), self._i_bits, self.module_fault)

    # --- the message interface (the Exchanges component, tsx/messages.py) -----

    def submit(self, request: Request, now: int, on_done: OnDone) -> Exchange:
        """The PLC validated a Text Block addressed to this module."""
        return self.exchanges.submit(request, now, on_done)

    def overridden_requests(self) -> frozenset[int]:
        """Common request codes a subclass answers itself in handle_request."""
        return frozenset()

    def pending_exchange(self, channel: int) -> Exchange | None:
        return self.exchanges.pending(channel)

    def reset_exchanges(self, now: int, channel: int | None = None) -> None:
        """Cancel exchanges in progress (OWxy,0,2, or a channel reset bit)."""
        self.exchanges.reset(now, channel)

    def cancel_exchange(self, exchange: Exchange, now: int) -> None:
        """A Text Block's reset input cancels this one exchange."""
        self.reset_exchanges(now, exchange.request.channel)

    def on_exchange_cancelled(self, exchange: Exchange, now: int) -> None:
        """An exchange is about to be cancelled: stop what it started."""

    @property
    def _exchanges(self) -> dict[int, Exchange]:
        """The exchanges by key (a subclass holding one under its own key uses it)."""
        return self.exchanges.by_key

    # --- faults by name (docs/aem811.md): each kind's table, through the host ----

    def fault_names(self) -> Mapping[str, str]:
        """name -> description of every fault this core takes by name."""
        return cast(Any, host()).fault_names(self)  # type: ignore[no-any-return]

    fault_names.through_table = True  # type: ignore[attr-defined]  # (devices.faults)

    def inject_fault(self, name: str, active: bool) -> None:
        """Set or clear a fault by its name: the kind's table (fieldtwin.devices) maps
        it to this core's typed call; ConfigError naming what is allowed."""
        cast(Any, host()).inject_fault(self, name, active)

    # --- status for people -------------------------------------------------

    def status(self) -> dict[str, str]:
        """The lines every module shows (its kind's own lines: ``devices/<kind>/status.py``)."""
        lines = {
            "module": f"{self.type_name} rack {self.rack} slot {self.slot}",
            "state": self.state.value,
            **({"mode": "Run" if self.running else "Stop"} if self.has_run_stop else {}),
            "leds": self.led_text,
            "fault (I,S)": str(int(self.module_fault)),
        }
        if not self.code_ok:
            lines["code"] = f"declared code {self.declared_code} is not this module's"
        return lines


def _lit(*names: str) -> dict[str, LedState]:
    return {name: "on" if name in names else "off" for name in ("OK", "ERR", "F")}


_M = IntelligentModule
# The operating modes (AEM 2.5, 7.1-1; SCM 6.4): power-up runs the initial self-test,
# which ends operational (Run/Stop by IWxy,0,C) or blocked; power off from anywhere.
MODES: Table[ModuleState, ModuleEvent] = Table(
    "module modes",
    ModuleState,
    ModuleEvent,
    {
        (ModuleState.OFF, ModuleEvent.POWER_ON): (_M._start_self_test, ModuleState.SELF_TEST),
        (ModuleState.OFF, ModuleEvent.POWER_OFF): (None, ModuleState.OFF),
        (ModuleState.SELF_TEST, ModuleEvent.SELF_TEST_DONE): (
            _M._end_self_test,
            ModuleState.OPERATIONAL,
        ),
        (ModuleState.SELF_TEST, ModuleEvent.BLOCKING_FAULT): (_M._block, ModuleState.BLOCKED),
        (ModuleState.SELF_TEST, ModuleEvent.POWER_OFF): (_M._power_down, ModuleState.OFF),
        (ModuleState.OPERATIONAL, ModuleEvent.BLOCKING_FAULT): (_M._block, ModuleState.BLOCKED),
        (ModuleState.OPERATIONAL, ModuleEvent.POWER_OFF): (_M._power_down, ModuleState.OFF),
        (ModuleState.BLOCKED, ModuleEvent.BLOCKING_FAULT): (None, ModuleState.BLOCKED),
        (ModuleState.BLOCKED, ModuleEvent.POWER_OFF): (_M._power_down, ModuleState.OFF),
    },
)


__all__ = [
    "MODES",
    "BusImage",
    "FaultCategory",
    "IntelligentModule",
    "LedState",
    "ModuleContext",
    "ModuleEvent",
    "ModuleState",
]
