"""The PLC: models, racks and slots, the master task and its bus refresh, Text Blocks.

Each master-task cycle ends by refreshing the I/O bus: the PLC reads the modules'
input bits and words into its image and writes its output image to them
(register words every cycle, or every second cycle on a TSX 47-20: AEM 2.4-3).
A Text Block is validated at the end of the master task (AEM 4.2-2 "the request
is validated at the end of the master task when the outputs are updated") and
its report appears at the end of a later cycle.

The task watchdog (docs/pl7.md, docs/manual-notes.md W-1): a master task that runs
past its budget is cut; the PLC goes to its fault state (``fault`` says why, SY11
reads 1, ``mode`` is FAULT): the master task no longer runs, the discrete outputs
fall back to 0 (written to the modules at once), the register words keep their
last value, the bus keeps being refreshed.  ``on_fault`` (the plant's event stream)
is told.  The way back: a cold restart (``plc cold``, the console's init), a hot
restart (``plc hot``: the program sees SY11), loading a program, or a power break
longer than the power reserve; ``start`` (``plc run``) is refused while in fault.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

from fieldtwin import hosting
from fieldtwin.clock import MS, Handle, S, SimClock, seconds
from fieldtwin.errors import ConfigError
from fieldtwin.pl7.executor import WATCHDOG_MS, Executor, budget_of
from fieldtwin.pl7.tree import Internal
from fieldtwin.textfile import MiB, read_text
from fieldtwin.tsx import registry
from fieldtwin.tsx.addressing import ObjectKind, ObjectRef, parse_object
from fieldtwin.tsx.bus import Host, Pacer
from fieldtwin.tsx.module import BusImage, IntelligentModule, ModuleContext
from fieldtwin.tsx.plcmemory import (
    CONSTANT_WORDS,
    INTERNAL_BITS,
    SYSTEM_BITS,
    SYSTEM_WORDS,
    PlcMemory,
    TxtDeclaration,
    calendar_words,
    days_from_civil,
)
from fieldtwin.tsx.slots import ABSENT, MODELS, Slot
from fieldtwin.tsx.textblock import ERR_MODULE_FAULT, ERR_POWER_BREAK
from fieldtwin.tsx.txt import (
    DATA_WORDS,
    ExchangeResult,
    ExchangeTimeout,
    TextBlock,
    TextBlocks,
)
from fieldtwin.words import (
    format_hex,
    get_bit,
    set_bit,
    to_signed,
    to_unsigned,
)

M = TypeVar("M", bound=IntelligentModule)
ModuleOption = bool | int | float | str  # a module's own constructor option (quantize...)


HALF_MINUTE_US = 30 * S  # SY7 flips every half minute (pl7.executor)
PARK_MAX_US = 1 * S  # a parked task event at most this far ahead with nothing scheduled
POWER_RESERVE_US = 10 * MS  # a shorter break does not restart the modules (F-9)
MAX_PROGRAM_BYTES = 1 * MiB  # a program file read (the tokenizer's bound is 1,000,000 characters)
WATCHDOG_RANGE_MS = (10, 500)  # the task watchdog periods a plant may give (W-1)
_W_RE = re.compile(r"^W(\d{1,5})$", re.IGNORECASE)
_INTERNAL_RE = re.compile(r"^(XM|X|B|CW|SY|SW|W)(\d{1,5})(?:,([0-9A-F]))?$", re.IGNORECASE)


class Plc:
    """A TSX Series 7 PLC with intelligent modules in its racks."""

    def __init__(
        self,
        model: str = "TSX 87",
        scan_ms: float = 10,
        *,
        clock: SimClock | None = None,
        runner: Pacer | None = None,
        speed: float | None = 1.0,
        host: Host | None = None,
        event_driven: bool = True,
        watchdog_ms: float = WATCHDOG_MS,
        park: bool = True,
    ) -> None:
        if model not in MODELS:
            raise ConfigError(f"unknown PLC model {model!r} (allowed: {', '.join(MODELS)})")
        if not 1 <= scan_ms <= 1000:
            raise ConfigError(f"scan_ms {scan_ms} out of range (allowed 1..1000 ms)")
        low, high = WATCHDOG_RANGE_MS
        if not low <= watchdog_ms <= high:
            raise ConfigError(f"watchdog_ms {watchdog_ms} out of range (allowed {low}..{high} ms)")
        self.watchdog_ms = watchdog_ms
        self.model = MODELS[model]
        self.scan_us = round(scan_ms * MS)
        self.clock = clock or SimClock()
        self.runner = runner
        self.host = host  # None: fieldtwin.hosting's, asked when a real endpoint is wired
        self.speed = speed
        self.running = True
        self.fault: str | None = None  # why the PLC is in its fault state (the watchdog)
        # told (simulated time in µs, the reason) when the watchdog trips: the plant's
        # event stream (fieldtwin.plant)
        self.on_fault: Callable[[int, str], None] | None = None
        self._powered = True
        self._cycles = 0
        self.txt = TextBlocks(self.model.table_max, self.model.report_name, self._lookup)
        self.data = self.txt.data  # internal words W0..W4095
        self.bits = [0] * INTERNAL_BITS  # B0..B4095
        self.cw = [0] * CONSTANT_WORDS  # CW0..CW4095 (the plant file's constants)
        self.sy = [0] * SYSTEM_BITS  # SY0..SY127
        self.sw = [0] * SYSTEM_WORDS  # SW0..SW127
        self.memory = PlcMemory(self)
        self.program: Executor | None = None
        self.program_source = ""
        self.watch = [f"W{i}" for i in range(8)]  # the words the live view shows
        self.calendar_epoch_s: int | None = None  # SW51..SW56 at simulated time 0
        self._slots: dict[tuple[int, int], Slot] = {}
        # The bus refresh (see _end_of_task): event-driven, a slot is refreshed only
        # after its module's bus face changed (module.bus_dirty) or the PLC's output
        # image may have changed, and a program's idle tasks are skipped (pl7/watch.py);
        # else every slot and the whole program at every task, as the real PLC does
        # (kept for the benchmarks' baseline and the equivalence tests).
        self.event_driven = event_driven
        self._bus_pending = False  # a module's face changed since the last refresh
        self._outputs_touched = False  # outputs written from outside the program
        self._calendar_words: tuple[int, list[tuple[int, int]]] = (-1, [])
        # Parking (docs/decisions.md, "Parking the idle master task"): after a task that
        # left everything as it found it, the next task event goes to the first task
        # instant at or after the next event of the clock (or an SY7 / calendar change);
        # the tasks in between are counted, not run.  False: an event at every task,
        # the reference of tests/tsx/test_parking.py.
        self.parks = park
        self._parked = False
        self._counted_to = 0  # while parked: the last task instant counted
        self._real_at = 0  # while parked: the first task instant that must really run
        self._phase = self.clock.now % self.scan_us  # the task instants' grid
        self._scan: Handle = self.clock.call_later(self.scan_us, self._end_of_task)

    # --- racks and slots -------------------------------------------------------

    def insert(
        self,
        type_name: str,
        rack: int = 0,
        slot: int = 0,
        *,
        code: int | None = None,
        **options: ModuleOption,
    ) -> IntelligentModule:
        """Put a module in a slot, powered; returns the module object."""
        cls: type[IntelligentModule] = registry.module_class(type_name)
        self._check_slot(rack, slot)
        self._check_limit(cls)
        make: Callable[..., IntelligentModule] = cls
        ctx = ModuleContext(self.clock, self.model.name, self._enable_pacing, self._open_line)
        module = make(ctx, rack, slot, declared_code=code, **options)
        self._wake()
        self._slots[(rack, slot)] = Slot(module)
        module.bus_listener = self._bus_changed
        self._bus_pending = True
        module.power_on()
        return module

    def _check_slot(self, rack: int, slot: int) -> None:
        if not 0 <= rack < self.model.racks:
            raise ConfigError(
                f"rack {rack} out of range for a {self.model.name}"
                f" (allowed 0..{self.model.racks - 1})"
            )
        if not 0 <= slot < self.model.intelligent_slots:
            raise ConfigError(
                f"slot {slot} cannot take an intelligent module in a {self.model.name}"
                f" (allowed 0..{self.model.intelligent_slots - 1})"
            )
        if (rack, slot) in self._slots:
            raise ConfigError(f"rack {rack} slot {slot} is already taken")
        in_basic = sum(1 for r, _ in self._slots if r == 0)
        if rack == 0 and in_basic >= self.model.basic_rack_max:
            raise ConfigError(
                f"slot {slot}: the basic rack of a {self.model.name} takes at most"
                f" {self.model.basic_rack_max} intelligent modules"
            )

    def _check_limit(self, cls: type[IntelligentModule]) -> None:
        """A per-kind limit of the configuration (DEM 6.2-2: 32 time-stamping modules)."""
        limit = cls.plc_limit
        if limit is None:
            return
        group, most = limit
        count = sum(1 for s in self._slots.values() if s.module.plc_limit == limit)
        if count >= most:
            raise ConfigError(
                f"{cls.type_name}: a PLC configuration takes at most {most} {group}"
                f" ({count} already inserted)"
            )

    def module(self, rack: int, slot: int) -> IntelligentModule:
        """The module in a slot (ConfigError naming the slot if there is none)."""
        return self._entry(rack, slot).module

    def module_as(self, cls: type[M], rack: int, slot: int) -> M:
        """The module in a slot as its own class (ConfigError if it is another kind)."""
        module = self.module(rack, slot)
        if not isinstance(module, cls):
            raise ConfigError(
                f"rack {rack} slot {slot} holds a {module.type_name}, not a {cls.type_name}"
            )
        return module

    @property
    def modules(self) -> list[IntelligentModule]:
        return [s.module for _, s in sorted(self._slots.items())]

    def remove(self, rack: int, slot: int) -> None:
        """Pull a module out of its slot under power."""
        entry = self._entry(rack, slot)
        self._wake()
        entry.present = False
        self._bus_pending = entry.module.bus_dirty = True  # the slot now reads ABSENT
        entry.module.power_off()
        # AEM 4.4-1 "module absent" is a module fault: TXTi,S = 4, not a power break
        self.txt.end_all(ERR_MODULE_FAULT, self.clock.now, (rack, slot))

    def reinsert(self, rack: int, slot: int) -> None:
        """Put a pulled module back: it runs its initial self-test."""
        entry = self._entry(rack, slot)
        self._wake()
        if not entry.present:
            entry.present = True
            entry.module.power_on()

    def _entry(self, rack: int, slot: int) -> Slot:
        try:
            return self._slots[(rack, slot)]
        except KeyError:
            raise ConfigError(f"no module in rack {rack} slot {slot}") from None

    # --- time ------------------------------------------------------------------

    def _enable_pacing(self) -> Pacer:
        """A module wired a real endpoint: time now follows the wall clock."""
        if self.runner is None:
            self.runner = self._host().pacer(self.clock, self.speed)
        return self.runner

    def _open_line(self, url: str, line: object) -> object:
        """A module wires a real endpoint: the host opens it, paced by the PLC's pacer."""
        return self._host().open_line(url, line, self._enable_pacing())

    def _host(self) -> Host:
        if self.host is None:
            found = hosting.host()
            if not isinstance(found, Host):
                raise ConfigError(f"{found!r} is not a host (pacer, open_line)")
            self.host = found
        return self.host

    def advance(self, duration_s: float) -> None:
        """Run the simulation for ``duration_s`` simulated seconds."""
        if not 0 <= duration_s * S < float("inf"):
            raise ConfigError(f"cannot advance by {duration_s} s (allowed 0 or more seconds)")
        self._advance_us(seconds(duration_s))

    def advance_to(self, t_s: float) -> None:
        """Run the simulation until simulated time ``t_s`` (seconds since the start)."""
        if not t_s * S < float("inf") or seconds(t_s) < self.clock.now:
            raise ConfigError(
                f"cannot advance to t = {t_s} s: simulated time is already"
                f" {self.now_s:.6f} s and never goes back"
            )
        self._advance_us(seconds(t_s) - self.clock.now)

    def _advance_us(self, duration: int) -> None:
        if self.runner is not None:
            self.runner.advance(duration)
        else:
            self.clock.advance(duration)

    def _run_until(self, predicate: Callable[[], bool], limit: int) -> bool:
        if self.runner is not None:
            return bool(self.runner.run_until(predicate, limit))
        end = self.clock.now + limit
        while not predicate():
            deadline = self.clock.next_deadline()
            if deadline is None or deadline > end:
                self.clock.run_until(end)
                break
            self.clock.run_until(deadline)
        return predicate()

    @property
    def now(self) -> int:
        """Simulated time in microseconds (the same as ``now_us``)."""
        return self.clock.now

    @property
    def now_us(self) -> int:
        """Simulated time in integer microseconds."""
        return self.clock.now

    @property
    def now_s(self) -> float:
        """Simulated time in seconds since the PLC's clock started."""
        return self.clock.now / S

    # --- the master task and the bus ------------------------------------------

    def _bus_changed(self, module: IntelligentModule) -> None:
        self._bus_pending = True
        if self._parked:
            self._wake()

    @property
    def cycles(self) -> int:
        """Master tasks so far (while powered)."""
        return self._cycles + self._owed()

    def _end_of_task(self, now: int) -> None:
        if self._parked:
            if now < self._real_at and self.parks and self.event_driven:
                self._idle_tasks(now)  # nothing changed: each task would skip
                return
            self._unpark()  # an SY7 / calendar change: this task really runs
        # the clock calls this at ``now`` = its time: call_later(scan_us) without the check
        self._scan = self.clock.schedule(now + self.scan_us, self._end_of_task)
        if not self._powered:
            return
        self._cycles += 1
        program = self.program
        wrote = program is not None  # the program may have written the output image
        if program is not None and self.running:  # PRE, CHART, POST on the input image
            if self.calendar_epoch_s is not None:
                for word, value in self._calendar(self.calendar_epoch_s + now // S):
                    self.sw[word] = value
            skipped = program.skipped
            program.skip_idle = self.event_driven  # else every task runs, as on the PLC
            program.run_master_task(now)
            wrote = program.skipped == skipped  # a skipped task wrote nothing
            if program.overrun is not None:
                self._watchdog(program, now)
        registers = self._cycles % self.model.register_every == 0
        if not self.event_driven:
            for entry in self._slots.values():
                self._refresh(entry, registers, now)
        elif (wrote or self._outputs_touched or self._bus_pending) and self._refresh_changed(
            wrote, registers, now
        ):
            wrote = True  # a new input image: the next task sees it
        self.txt.end_of_task(now, self.running)
        if self.parks and not wrote and self._idle(program):
            self._park(now)

    # --- parking the idle master task ---------------------------------------------
    #
    # A task is idle when the program skipped it (a fixed point: pl7/watch.py) or there
    # is none, no bus face or output changed, and no Text Block is at work: the next
    # task would do the same nothing, and so would every task after it until something
    # the PLC sees changes.  What can change it: a module's bus face (its listener), a
    # write or a command through the Plc's methods, the executor's controls
    # (breakpoints, hold, restarts: ``on_touch``), power, and time itself (SY7 every
    # 30 s, the calendar words every second).  While parked, the next task event is at
    # the first task instant at or after the clock's next event (or that SY7 / calendar
    # change): no event runs between, so nothing can change before it.  Its sequence
    # number is taken where the unparked run would take it (at the virtual task before
    # it, when nothing else runs in between), so the events of its instant run in the
    # same order as without parking.  An event scheduled from outside a run (a command,
    # bytes delivered, a test) puts the next task back to the first instant after now,
    # where the unparked run has it.  The tasks counted meanwhile appear in ``cycles``
    # and the executor's ``cycles`` and ``skipped`` as soon as their instant is past.

    def _idle(self, program: Executor | None) -> bool:
        if not self.event_driven or self._bus_pending or self._outputs_touched:
            return False
        if program is not None and (
            not self.running or program.held is not None or program.overrun is not None
        ):
            return False
        if self.txt.busy():
            return False
        return not any(entry.module.bus_dirty for entry in self._slots.values())

    def _grid(self, at: int) -> int:
        """The first task instant at or after ``at``."""
        return at + (self._phase - at) % self.scan_us

    def _park(self, now: int) -> None:
        """After an idle real task at ``now``: the next task event moves on (or stays)."""
        handle = self._scan  # the unparked run's next task, scheduled by this one
        self._parked = True
        self._counted_to = now
        if self.program is not None:
            self.program.owed = self._owed
        self.clock.outside_watchers.append(self._realign)
        at = self._skip_to(now, self.clock.next_deadline_besides(handle))
        if at != handle.time:  # else it stays, with the sequence number it took
            handle.cancel()
            # nothing runs between now and ``at`` but the virtual tasks, so this is the
            # order the last of them (at ``at`` - scan) would give it
            self._scan = self.clock.schedule_as(at, self.clock.reserve(), self._end_of_task)

    def _skip_to(self, now: int, top: int | None) -> int:
        """The next task event: the first task instant at or after the clock's next event
        ``top`` or the next change of SY7 / the calendar words, at least the next task."""
        scan = self.scan_us
        bound = self._time_bound(now)
        limit = now + PARK_MAX_US if top is None else top
        if bound is not None:
            limit = min(limit, bound)
            self._real_at = self._grid(bound)
        else:
            self._real_at = now + PARK_MAX_US + scan
        return max(now + scan, self._grid(limit))

    def _time_bound(self, now: int) -> int | None:
        """When the next task would see time itself change something: SY7 (the minute
        bit, flipping every 30 s) and the calendar words SW51..SW56 (every second),
        both written only while a program runs."""
        if self.program is None or not self.running:
            return None
        bound = (now // HALF_MINUTE_US + 1) * HALF_MINUTE_US
        if self.calendar_epoch_s is not None:
            bound = min(bound, (now // S + 1) * S)
        return bound

    def _idle_tasks(self, now: int) -> None:
        """The parked task event fired at ``now`` with nothing changed: the tasks up to
        ``now`` are counted as skipped, and the next event goes on."""
        tasks = (now - self._counted_to) // self.scan_us
        self._cycles += tasks
        program = self.program
        if program is not None:
            program.count_idle(tasks)
        self._counted_to = now
        clock = self.clock
        at = self._skip_to(now, clock.next_deadline())
        # the sequence number the unparked task at ``now`` would take for the next one
        self._scan = clock.schedule_as(at, clock.reserve(), self._end_of_task)

    def _owed(self) -> int:
        """While parked: the idle tasks whose instant is past and not yet counted."""
        if not self._parked:
            return 0
        last = min(self.clock.now, self._scan.time - self.scan_us)
        return max(0, (last - self._counted_to) // self.scan_us)

    def _realign(self) -> None:
        """Outside a run: the next task event no later than the first task instant after
        now (where the unparked run has it), with the sequence number it holds."""
        handle, at = self._scan, self._grid(self.clock.now + 1)
        if self._parked and handle.time > at:
            seq = handle.seq
            handle.cancel()
            self._parked = False  # the schedule below tells the watchers: not this one
            self._scan = self.clock.schedule_as(at, seq, self._end_of_task)
            self._parked = True

    def _wake(self) -> None:
        """Something the next task may see changed: it runs at its event."""
        if self._parked:
            self._realign()
            self._unpark()

    def _unpark(self) -> None:
        """The idle tasks before the task event are counted; the event runs a task."""
        tasks = (self._scan.time - self._counted_to) // self.scan_us - 1
        self._cycles += tasks
        program = self.program
        if program is not None:
            program.count_idle(tasks)
            program.owed = None
        self._parked = False
        self.clock.outside_watchers.remove(self._realign)

    def _calendar(self, epoch_s: int) -> list[tuple[int, int]]:
        """SW51..SW56 of ``epoch_s``, computed once a second (written at every task)."""
        if self._calendar_words[0] != epoch_s:
            self._calendar_words = (epoch_s, list(calendar_words(epoch_s).items()))
        return self._calendar_words[1]

    def _refresh_changed(self, outputs: bool, registers: bool, now: int) -> bool:
        """The event-driven bus refresh, with the same result as ``_refresh`` on every
        slot: the outputs are written where the output image differs from what the
        module holds, the input image is read again only from a module whose face
        changed (its images are equal to what a read would give: the property tests
        in tests/tsx/test_bus_refresh.py), in slot order, as the real PLC does.
        True if an input image changed."""
        changed = False
        outputs = outputs or self._outputs_touched
        # a TSX 47-20 odd cycle writes the bits only: the words at the next cycle
        self._outputs_touched = outputs and not registers
        self._bus_pending = False
        for entry in self._slots.values():
            module = entry.module
            if not (outputs or module.bus_dirty):
                continue
            if not entry.present:  # AEM 4.4-1: IWxy,0,8 "module absent", Ixy,S
                changed = changed or entry.image is not ABSENT
                entry.image = ABSENT
                module.bus_dirty = False
                continue
            o_bits = entry.outputs[0]
            if registers:
                if o_bits != module.o_bits or entry.ow != module.ow:
                    module.bus_write(entry.ow, o_bits, now)
            elif o_bits != module.o_bits:
                module.bus_write(module.ow, o_bits, now)
            if not module.bus_dirty:
                continue
            image = entry.image
            i_bits, fault = module.i_bits, module.module_fault
            if registers:
                module.bus_dirty = False
                iw = tuple(module.iw)
                if image.iw != iw or image.i_bits != i_bits or image.fault != fault:
                    entry.image = BusImage(iw, i_bits, fault)
                    changed = True
            else:  # TSX 47-20 odd cycle: discrete bits only; the words at the next one
                self._bus_pending = True
                if image.i_bits != i_bits or image.fault != fault:
                    entry.image = BusImage(image.iw, i_bits, fault)
                    changed = True
        return changed

    def _refresh(self, entry: Slot, registers: bool, now: int) -> None:
        """The bus refresh of one slot at every task (``event_driven=False``)."""
        module = entry.module
        if not entry.present:  # AEM 4.4-1: IWxy,0,8 "module absent", Ixy,S
            entry.image = ABSENT
            return
        if registers:
            module.bus_write(entry.ow, entry.o_bits, now)
        elif entry.o_bits != module.o_bits:
            module.bus_write(module.ow, entry.o_bits, now)
        if registers:
            entry.image = module.bus_read()
        else:  # TSX 47-20 odd cycle: discrete bits only
            image = module.bus_read()
            entry.image = BusImage(entry.image.iw, image.i_bits, image.fault)

    # --- PLC modes -------------------------------------------------------------

    @property
    def mode(self) -> str:
        """RUN, STOP, or FAULT (stopped by the watchdog: ``fault`` says why)."""
        if self.fault is not None:
            return "FAULT"
        return "RUN" if self.running else "STOP"

    def _watchdog(self, program: Executor, now: int) -> None:
        """The master task overran its budget: the PLC to its fault state."""
        over = program.overrun
        assert over is not None
        self.running = False
        self.fault = (
            f"watchdog: master task exceeded {program.budget} operations"
            f" ({self.watchdog_ms:g} ms) in {over.module} line {over.line}, task {over.cycle}"
        )
        for entry in self._slots.values():
            entry.o_bits = 0  # the discrete outputs fall back to 0 (W-1)
        self._outputs_touched = True
        if self.on_fault is not None:
            self.on_fault(now, self.fault)

    def _clear_fault(self) -> None:
        self.fault = None

    def stop(self) -> None:
        """PLC to STOP: the master task no longer runs (the bus keeps its image)."""
        self._wake()
        self.running = False

    def start(self) -> None:
        """PLC to RUN (refused in the watchdog's fault: a restart is the way back)."""
        if self.fault is not None:
            raise ConfigError(
                f"the PLC is in its fault state ({self.fault}): fix the program"
                " (prog load), then plc cold (a cold restart, SY0) or plc hot (SY1,"
                " SY11 kept); RUN alone is refused"
            )
        self._wake()
        self.running = True

    def cold_restart(self) -> None:
        """SY0: modules re-initialised (AEM 2.5-3), images and Text Blocks cleared."""
        self._wake()
        present = [e for e in self._slots.values() if e.present]
        for entry in present:  # off first: a module sees the exchange it was doing cut
            entry.module.power_off()
        self._end_exchanges(ERR_POWER_BREAK)
        for entry in self._slots.values():
            entry.ow[:] = [0] * 8  # in place: a program's compiled cells are these lists
            entry.o_bits = 0
        self._outputs_touched = True
        for entry in present:
            entry.module.power_on()
        if self.program is not None:  # SY0; internal bits and words cleared
            self.program.cold_restart()
        self._clear_fault()
        self.running = True

    def hot_restart(self) -> None:
        """SY1: the program resumes; modules and internal objects keep their state."""
        self._wake()
        if self.program is not None:
            self.program.hot_restart()
        self._clear_fault()
        self.running = True

    def power_break(self, duration_s: float) -> None:
        """Cut the PLC supply for ``duration_s`` (simulated).  A break longer than the
        power reserve ends in a hot restart: SY1 reads 1 during the first master task,
        internal objects are kept and the modules must be reconfigured (AEM 2.5-3,
        DEM 2.5-3 "on a warm restart, when the power reserve has been exhausted")."""
        power_back = self.cut_power(duration_s)
        try:
            self._advance_us(seconds(duration_s))
        finally:
            self._powered = True
        power_back()

    def cut_power(self, duration_s: float) -> Callable[[], None]:
        """The first half of ``power_break``: the supply cut for a break of ``duration_s``;
        the second half, the power's return, is the function returned (the control API
        runs the break as a runner mode between the two, docs/control.md)."""
        if not 0 <= duration_s * S < float("inf"):
            raise ConfigError(f"power break of {duration_s} s not allowed (allowed 0 or more)")
        long_break = seconds(duration_s) > POWER_RESERVE_US
        self._wake()  # the tasks before the break are counted; none during it
        present = [e for e in self._slots.values() if e.present]
        if long_break:  # off first: a module sees the exchange it was doing cut
            for entry in present:
                entry.module.power_off()
        self._end_exchanges(ERR_POWER_BREAK)
        self._powered = False  # no master task, no bus refresh during the break

        def power_back() -> None:
            self._wake()
            self._powered = True
            if long_break:
                for entry in present:
                    entry.module.power_on()
            self._read_inputs()
            if long_break and self.program is not None:  # AEM 2.5-3, DEM 2.5-3: SY1 = 1
                self.program.hot_restart()
            if long_break and self.fault is not None:  # a power cycle ends the fault
                self._clear_fault()
                self.running = True

        return power_back

    def _read_inputs(self) -> None:
        """Power return: the input image is read again from the modules at once, so
        that it shows what they do now (a self-test after a long break), not what they
        did before the break.  The output image and the internal words are kept."""
        for entry in self._slots.values():
            entry.image = entry.module.bus_read() if entry.present else ABSENT

    def _end_exchanges(self, code: int) -> None:
        self.txt.end_all(code, self.clock.now)

    # --- objects -----------------------------------------------------------------

    def read(self, name: str) -> int:
        """An object by its PL7 name: 0/1 for a bit, 0..65535 for a word."""
        w = self._w_address(name)
        if w is not None:
            return self.data[w]
        internal = self._internal(name)
        if internal is not None:
            return internal()
        ref = parse_object(name)
        entry = self._entry(ref.rack, ref.slot)
        if ref.kind is ObjectKind.FAULT:
            return int(entry.image.fault)
        if ref.kind is ObjectKind.I:
            return get_bit(entry.image.i_bits, _index(ref))
        if ref.kind is ObjectKind.O:
            return get_bit(entry.o_bits, _index(ref))
        word = entry.image.iw[_index(ref)] if ref.kind is ObjectKind.IW else entry.ow[_index(ref)]
        return get_bit(word, ref.bit) if ref.bit is not None else word

    def read_signed(self, name: str) -> int:
        """A word (IWxy,i, OWxy,i or Wi) as a signed 16-bit integer: -32768..32767."""
        w = self._w_address(name)
        if w is None:
            ref = parse_object(name)
            if ref.kind not in (ObjectKind.IW, ObjectKind.OW) or ref.bit is not None:
                raise ConfigError(f"{name!r} is not a word: read_signed takes IWxy,i, OWxy,i or Wi")
        return to_signed(self.read(name))

    def write(self, name: str, value: int) -> None:
        """Write an output object (OWxy,i / OWxy,i,j / Oxy,i) or an internal word Wi."""
        self._wake()
        w = self._w_address(name)
        if w is not None:
            self.data[w] = to_unsigned(value)
            return
        match = _INTERNAL_RE.match(name.strip())
        if match is not None:
            self._write_internal(name, match, value)
            return
        ref = parse_object(name)
        entry = self._entry(ref.rack, ref.slot)
        self._outputs_touched = True
        if ref.kind is ObjectKind.OW:
            i = _index(ref)
            if ref.bit is None:
                entry.ow[i] = to_unsigned(value)
            else:
                entry.ow[i] = set_bit(entry.ow[i], ref.bit, _bit_value(name, value))
            return
        if ref.kind is ObjectKind.O:
            outputs = entry.module.discrete_outputs
            if _index(ref) >= outputs:
                raise ConfigError(
                    f"{name!r}: {entry.module.type_name} has "
                    + (
                        f"discrete outputs O,0..O,{outputs - 1:X}"
                        if outputs
                        else "no discrete outputs"
                    )
                )
            entry.o_bits = set_bit(entry.o_bits, _index(ref), _bit_value(name, value))
            return
        raise ConfigError(
            f"{name!r} is an input: only outputs (OWxy,i, OWxy,i,j, Oxy,i) and the PLC's"
            " internal objects (Wi, Wi,j, Bi, CWi, SYi, SWi) can be written"
        )

    # --- the program (fieldtwin.pl7) ------------------------------------------------

    def load_program(self, path_or_text: str | Path, source: str = "") -> Executor:
        """Load a PL7-3 program (a file's path, or its text): a cold restart of the
        program (SY0, internal bits and words cleared; docs/pl7.md); it runs at every
        master task from now on.  A refused program is a Pl7Error (line, column, token)."""
        text, name = _program_text(path_or_text)
        executor = Executor.from_source(text, self.memory, source=source or name)
        executor.budget = budget_of(self.watchdog_ms)
        self._wake()
        executor.on_touch = self._wake
        self.program, self.program_source = executor, text
        if self.fault is not None:  # a new program after the watchdog: a cold restart
            self._clear_fault()
            self.running = True
        return executor

    def set_calendar(
        self, year: int, month: int, day: int, hour: int = 0, minute: int = 0, second: int = 0
    ) -> None:
        """The PLC's date and time now (SW51..SW56 follow simulated time from here)."""
        if not (1980 <= year <= 2079 and 1 <= month <= 12 and 1 <= day <= 31):
            raise ConfigError(f"date {year}-{month}-{day} not allowed (1980..2079)")
        if not (0 <= hour < 24 and 0 <= minute < 60 and 0 <= second < 60):
            raise ConfigError(f"time {hour}:{minute}:{second} not allowed")
        epoch = days_from_civil(year, month, day) * 86400 + hour * 3600 + minute * 60 + second
        self._wake()
        self.calendar_epoch_s = epoch - self.clock.now // S

    def unload_program(self) -> None:
        self._wake()
        self.program = None
        self.program_source = ""

    def declare_text_block(self, index: int, declaration: TxtDeclaration) -> None:
        """How TXTi's tables are declared (configuration mode): see plcmemory."""
        self.txt.block(index)  # ConfigError past TXT63
        self._wake()
        self.memory.declarations[index] = declaration

    def slot_entry(self, rack: int, slot: int) -> Slot:
        """The slot's images (the program's module objects: with a program loaded,
        the outputs are compared with the modules' at every task)."""
        return self._entry(rack, slot)

    def _internal(self, name: str) -> Callable[[], int] | None:
        match = _INTERNAL_RE.match(name.strip())
        if match is None:
            return None
        kind, index, bit = match.group(1).upper(), int(match.group(2)), match.group(3)
        if kind in ("X", "XM"):
            program = self.program
            if program is None or program.layout is None:
                raise ConfigError(f"{name!r}: the PLC runs no program with a chart")
            if kind == "X":
                return lambda: int(program.step_active(str(index)))
            cells, at = program.step_cells(Internal("XM", index))
            return lambda: int(any(cells[k] for k in at))
        table = self._internal_table(name, kind, index)
        if bit is None:
            return lambda: table[index]
        b = int(bit, 16)
        return lambda: (table[index] >> b) & 1

    def _internal_table(self, name: str, kind: str, index: int) -> list[int]:
        tables = {"B": self.bits, "CW": self.cw, "SY": self.sy, "SW": self.sw, "W": self.data}
        table = tables[kind]
        if index >= len(table):
            raise ConfigError(f"{name!r}: out of range (allowed {kind}0..{kind}{len(table) - 1})")
        return table

    def _write_internal(self, name: str, match: re.Match[str], value: int) -> None:
        kind, index, bit = match.group(1).upper(), int(match.group(2)), match.group(3)
        if kind in ("X", "XM"):
            raise ConfigError(f"{name!r} is a step: the chart sets it (allowed: B, W, CW, SY, SW)")
        table = self._internal_table(name, kind, index)
        if kind in ("B", "SY") or bit is not None:
            v = _bit_value(name, value)
            if bit is None:
                table[index] = v
            else:
                table[index] = set_bit(table[index], int(bit, 16), v)
            return
        table[index] = to_unsigned(value)

    def _w_address(self, name: str) -> int | None:
        match = _W_RE.match(name.strip())
        if match is None:
            return None
        address = int(match.group(1))
        if address >= DATA_WORDS:
            raise ConfigError(
                f"{name!r}: internal word out of range (allowed W0..W{DATA_WORDS - 1})"
            )
        return address

    # --- Text Blocks (fieldtwin.tsx.txt) ---------------------------------------------

    def text_block(self, index: int) -> TextBlock:
        return self.txt.block(index)

    def start_exchange(
        self,
        m: int,
        c: int,
        send: Sequence[int] | None = None,
        *,
        send_bytes: bytes | None = None,
        length: int | None = None,
        recv_bytes: int = 0,
        txt: int = 0,
        table: int | None = None,
        indirect: int | None = None,
        recv_table: int | None = None,
    ) -> TextBlock:
        """Set a Text Block's inputs and start it (see TextBlocks.start); no waiting.

        Returns the Text Block as the exchange's handle: ``done`` (TXTi,D),
        ``result`` (an ExchangeResult once done, else None) and ``ended_at``
        (simulated seconds when it ended, else None).  It is validated at the end
        of the master task; advance time (``advance``, ``advance_to``) to see it end.
        """
        self._wake()
        return self.txt.start(
            m,
            c,
            send,
            send_bytes=send_bytes,
            length=length,
            recv_bytes=recv_bytes,
            txt=txt,
            table=table,
            indirect=indirect,
            recv_table=recv_table,
        )

    def reset_text_block(self, txt: int) -> None:
        """The Text Block's R input: the exchange in progress ends with TXTi,S = 1."""
        self._wake()
        self.txt.reset(txt, self.clock.now)

    def exchange(
        self,
        m: int,
        c: int,
        send: Sequence[int] | None = None,
        *,
        timeout_s: float = 1200.0,
        send_bytes: bytes | None = None,
        length: int | None = None,
        recv_bytes: int = 0,
        txt: int = 0,
        table: int | None = None,
        indirect: int | None = None,
        recv_table: int | None = None,
    ) -> ExchangeResult:
        """Start a Text Block exchange and run the simulation until it ends (bounded
        by ``timeout_s`` simulated seconds: ExchangeTimeout); keywords as start_exchange."""
        tb = self.start_exchange(
            m,
            c,
            send,
            send_bytes=send_bytes,
            length=length,
            recv_bytes=recv_bytes,
            txt=txt,
            table=table,
            indirect=indirect,
            recv_table=recv_table,
        )
        if not self._run_until(lambda: tb.done, seconds(timeout_s)) or tb.result is None:
            raise ExchangeTimeout(
                f"TXT{tb.index} (M={format_hex(m)}, C={format_hex(c, 2)}) not ended after"
                f" {timeout_s} simulated seconds (state {tb.state.value})"
            )
        return tb.result

    def _lookup(self, m: int) -> tuple[IntelligentModule, bool] | None:
        entry = self._slots.get(((m >> 12) & 0xF, (m >> 8) & 0xF))
        return None if entry is None else (entry.module, entry.present)

    # --- status ------------------------------------------------------------------

    def image(self, rack: int, slot: int) -> BusImage:
        return self._entry(rack, slot).image

    def output_words(self, rack: int, slot: int) -> list[int]:
        return list(self._entry(rack, slot).ow)


def _program_text(path_or_text: str | Path) -> tuple[str, str]:
    """A program's text and its name: a Path, or a str naming an existing .pl7 file,
    is read; any other str is the program itself."""
    if isinstance(path_or_text, str) and ("\n" in path_or_text or "%" in path_or_text):
        return path_or_text, ""
    path = Path(path_or_text)
    if isinstance(path_or_text, Path) or path.suffix.lower() == ".pl7" or path.exists():
        # a regular file of at most MAX_PROGRAM_BYTES of UTF-8: never a FIFO or a device
        return read_text(path, MAX_PROGRAM_BYTES, "PL7 program"), str(path)
    return str(path_or_text), ""


def _index(ref: ObjectRef) -> int:
    assert ref.index is not None
    return ref.index


def _bit_value(name: str, value: int) -> int:
    if value not in (0, 1):
        raise ConfigError(f"{name!r} is a bit: value {value} not allowed (allowed 0 or 1)")
    return value


__all__ = [
    "DATA_WORDS",
    "MAX_PROGRAM_BYTES",
    "MODELS",
    "WATCHDOG_MS",
    "WATCHDOG_RANGE_MS",
    "ExchangeResult",
    "ExchangeTimeout",
    "Plc",
    "TextBlock",
]
