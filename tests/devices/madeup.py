"""A made-up device added through the registry alone (docs/architecture.md, worked example).

The "TSX LVL 8" is not a real module: a level sensor card with one analog input
(``"0"``, volts, shown in IWxy,1 in millivolts), one analog output (``"0"``, the
valve it drives: OWxy,0 in millivolts, shown in volts with the word beside), one
fault (``float_stuck``, an application fault that sets IWxy,0,7), a port of a
kind of its own (``loop = "4-20"`` in the plant file: a current loop) carrying
a line fault with a parameter (``noise``, ``mv`` added to every sample; offered
only when the loop is there) and a stream (``level``: each sample in millivolts).
Its core, its adapter and its registry line are all in this file; nothing outside
it changes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import ClassVar

from fieldtwin.clock import S
from fieldtwin.devices import registry
from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import (
    Family,
    Fault,
    FaultParam,
    FrontPanel,
    Input,
    InputValue,
    Output,
    OutputValue,
    Port,
    PortKind,
    Publish,
    Reading,
    SignalSpec,
    Stream,
    applicable,
    pick_fault,
)
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.errors import ConfigError
from fieldtwin.signals import AnalogSignal, analog_from_spec
from fieldtwin.tsx.module import FaultCategory, IntelligentModule

LEVEL = "TSX LVL 8"
FLOAT_STUCK = 32  # an application fault bit of its fault string
SAMPLE_US = 100_000  # it samples its input every 100 ms
LOOP = PortKind("level loop", ("noise",))  # its current loop, and the fault it can carry
NOISE_MAX_MV = 1000


# --- the core (a sans-IO module, as tsx/<kind>/ would hold) ------------------------


class Level(IntelligentModule):
    type_name: ClassVar[str] = LEVEL
    self_test_us: ClassVar[int] = 1 * S
    has_run_stop: ClassVar[bool] = False

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.volts = 0.0
        self.signal: AnalogSignal | None = None
        self.noise_mv = 0  # the loop's noise fault: added to every sample
        self.tap: Callable[[int, int], None] | None = None  # (now, millivolts) per sample

    def on_self_test_done(self, now: int) -> None:
        self.call_later(SAMPLE_US, self._sample)

    def _sample(self, now: int) -> None:
        volts = self.signal.value_at(now) if self.signal is not None else self.volts
        self.iw[1] = max(0, min(0xFFFF, round(volts * 1000) + self.noise_mv))
        if self.tap is not None:
            self.tap(now, self.iw[1])
        self.call_later(SAMPLE_US, self._sample)

    def valve_mv(self) -> int:
        """The valve output: OWxy,0 as the program wrote it, in millivolts."""
        return self.ow[0]

    def fault_category_of(self, bit: int) -> FaultCategory:
        return FaultCategory.APPLICATION


# --- the adapter (as devices/<kind>.py would hold) ----------------------------------


class LevelDevice(ModuleDevice):
    def __init__(self, module: Level, plc: object) -> None:
        super().__init__(module, plc)  # type: ignore[arg-type]
        self.level = module
        self.loop: str | None = None  # the plant file's `loop`: its port, when wired

    def inputs(self) -> Mapping[str, Input]:
        return {"0": Input("0", "analog, volts", self._set, self._drive)}

    def _set(self, value: InputValue) -> None:
        try:
            self.level.volts = float(str(value).removesuffix("V"))
        except ValueError:
            raise ConfigError(f"input 0: {value!r} is not volts (e.g. 2.5V)") from None
        self.level.signal = None

    def _drive(self, spec: SignalSpec, where: str, base_dir: Path | None) -> None:
        self.level.signal = analog_from_spec(spec, where=where, base_dir=base_dir)

    def faults(self) -> Mapping[str, Fault]:
        return applicable(self._every_fault(), self.ports())

    def _every_fault(self) -> dict[str, Fault]:
        return {
            "float_stuck": Fault(
                "float_stuck",
                "the float switch is stuck",
                partial(self.level.set_fault, FLOAT_STUCK),
            ),
            "noise": Fault(
                "noise",
                f"the loop adds mv = 1..{NOISE_MAX_MV} to every sample",
                partial(self._noise, {}),
                ("mv",),
                lambda on, params: self._noise(params, on),
                state=self._noise_state,
                port_kinds=(LOOP.name,),
            ),
        }

    def fault(self, name: str) -> Fault:
        return pick_fault(self, name, self._every_fault())

    def _noise(self, params: Mapping[str, FaultParam], on: bool) -> None:
        mv = params.get("mv", 100) if on else 0
        if on and not (isinstance(mv, int) and 1 <= mv <= NOISE_MAX_MV):
            raise ConfigError(f"fault noise: mv = {mv!r} not allowed (allowed 1..{NOISE_MAX_MV})")
        self.level.noise_mv = int(mv)

    def _noise_state(self) -> Mapping[str, FaultParam] | None:
        return {"mv": self.level.noise_mv} if self.level.noise_mv else None

    def panel(self) -> FrontPanel:
        """Its LEDs, the level it measures (volts, flagged while the float is stuck)
        and the loop's noise: no window has a layout for it, each draws this."""
        mv = self.level.iw[1]
        stuck = ("float_stuck",) if self.level.fault_active(FLOAT_STUCK) else ()
        return FrontPanel(
            self.leds(),
            readings=(Reading("level", mv / 1000, "V", stuck, f"{mv} mV"),),
            fields=(("loop", self.loop or "not wired"), ("noise_mv", self.level.noise_mv)),
        )

    def outputs(self) -> Mapping[str, Output]:
        return {"0": Output("0", "analog, V (the valve)", self._valve)}

    def _valve(self) -> OutputValue:
        mv = self.level.valve_mv()
        return OutputValue("0", mv / 1000, "V", mv)

    def ports(self) -> list[Port]:
        if self.loop is None:
            return []
        return [Port("loop", f"loop:{self.loop}", "level", LOOP)]

    def streams(self) -> Sequence[Stream]:
        return (Stream("level", "each sample, in millivolts", self._subscribe),)

    def _subscribe(self, publish: Publish) -> Callable[[], None]:
        def tap(now: int, mv: int) -> None:
            publish(now, {"mv": mv})

        self.level.tap = tap
        return partial(setattr, self.level, "tap", None)

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        loop = table.get("loop")
        if loop is not None and not isinstance(loop, str):
            raise ConfigError(f'{where}.loop: {loop!r} is not a loop name (e.g. "4-20")')
        self.loop = loop
        inputs = table.get("inputs", {})
        if not isinstance(inputs, Mapping):
            raise ConfigError(f"{where}.inputs: a table of input = value or signal")
        apply_inputs(self, inputs, f"{where}.inputs", ctx.base_dir)
        apply_faults(self, table.get("faults", []), f"{where}.faults")


def build(table: Table, ctx: BuildContext, where: str) -> LevelDevice:
    module, plc = insert_module(table, ctx, where)
    assert isinstance(module, Level)
    device = LevelDevice(module, plc)
    device.configure(own_keys(table), ctx, where)
    return device


SCHEMA = Schema(
    IDENTITY,
    (
        Key("inputs", '{ "0" = volts or signal }'),
        Key("faults", "names"),
        Key("loop", 'its current loop, e.g. "4-20" (a port of kind "level loop")'),
    ),
)

# --- the registry line ----------------------------------------------------------------

registry.register(DeviceKind(LEVEL, Family.MODULE, SCHEMA, build, Level))
