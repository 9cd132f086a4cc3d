"""The EEPROM parameters TESIS edits (§3, §4) and their MP image (§6).

A parameter has a name, an allowed range (or set of choices), a factory value
(the Prm jumper settings of §3.1.2) and, for the "MP" words of the memory
map, the register it is loaded into at every power-on (§1, §6.1 glossary).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from types import MappingProxyType

from fieldtwin.errors import ConfigError
from fieldtwin.tes.models import Family, TesModel

Value = int | str

BAUDS = (1200, 2400, 4800, 9600, 19200, 38400)
PARITIES = ("N", "E", "O")
FILTER_SIZES = (2, 4, 8, 16, 32, 64, 128, 256)  # §4.2.3
THRESHOLD_TYPES = ("none", "simple", "hysteresis", "high_low")  # §4.2.6
NO_OUTPUT = -1
POINTS_MAX = 1023  # §4.2.4: inputs in points 0..1023
DAC_MAX = 32767  # §4.3.1 (AMB-TES-08)
CORRECTION_MAX = 10  # points; §4.2.5 "0,5% max" of 1023 is 5, twice allowed


@dataclass(frozen=True, slots=True)
class ParamSpec:
    name: str
    factory: Value
    help: str
    lo: int = 0
    hi: int = 0
    step: int = 1
    choices: tuple[Value, ...] = ()
    unit: str = ""

    def allowed(self) -> str:
        if self.choices:
            return ", ".join(str(c) for c in self.choices)
        step = f" by steps of {self.step}" if self.step > 1 else ""
        return f"{self.lo}..{self.hi}{step}"

    def parse(self, raw: object) -> Value:
        """A value typed by a user (str) or read from a file -> checked value."""
        value = self._coerce(raw)
        if self.choices:
            if value not in self.choices:
                raise ConfigError(
                    f"{self.name}: {raw!r} is not allowed (allowed: {self.allowed()})"
                )
            return value
        assert isinstance(value, int)
        if not self.lo <= value <= self.hi:
            raise ConfigError(f"{self.name}: {value} out of range (allowed {self.allowed()})")
        if value % self.step:
            raise ConfigError(
                f"{self.name}: {value} is not a multiple of {self.step} (allowed {self.allowed()})"
            )
        return value

    def _coerce(self, raw: object) -> Value:
        wants_int = not self.choices or isinstance(self.choices[0], int)
        if isinstance(raw, bool) or not isinstance(raw, int | str):
            raise ConfigError(f"{self.name}: {raw!r} is not a value (allowed {self.allowed()})")
        if not wants_int:
            return str(raw).strip()
        if isinstance(raw, int):
            return raw
        try:
            return int(raw.strip(), 0)
        except ValueError:
            raise ConfigError(
                f"{self.name}: {raw!r} is not a number (allowed {self.allowed()})"
            ) from None


def _link(prefix: str, baud: int) -> Iterator[ParamSpec]:
    # §3.1.3 / §3.1.4 link parameters; §7.2.7 answer delay 0..2570 ms
    yield ParamSpec(f"{prefix}.slave", 1, "slave number", 1, 247)
    yield ParamSpec(
        f"{prefix}.baud", baud, "speed (8 data bits, 1 stop bit)", choices=BAUDS, unit="Bd"
    )
    yield ParamSpec(f"{prefix}.parity", "E", "parity", choices=PARITIES)
    yield ParamSpec(f"{prefix}.answer_delay_ms", 0, "answer delay", 0, 2570, unit="ms")


def _digital(model: TesModel) -> Iterator[ParamSpec]:
    if model.digital_inputs:
        # §4.1.1 "between 0 and 32765 ms by steps of 5 ms"; §3.1.2 factory 5 ms
        yield ParamSpec(
            "filter_0_ms", 5, "input filter, confirmation of state 0", 0, 32765, 5, unit="ms"
        )
        yield ParamSpec(
            "filter_1_ms", 5, "input filter, confirmation of state 1", 0, 32765, 5, unit="ms"
        )
    # §4.1.6 blinking; §3.1.2 factory frequency 1 = 1 Hz, frequency 2 = 10 Hz
    for freq, half in (("a", 500), ("b", 50)):
        for state in ("on", "off"):
            yield ParamSpec(
                f"blink_{freq}_{state}_ms", half, f"frequency {freq.upper()}: duration {state}",
                0, 0xFFFF * 5, 5, unit="ms",
            )  # fmt: skip
    yield ParamSpec(
        "watchdog_100ms", 0, "master watching time, 0 = off (§3.1.3)", 0, 0xFFFF, unit="x100ms"
    )


def _masks(model: TesModel) -> Iterator[ParamSpec]:
    # §6.2.3.1 / §6.3.3 fallback masks; §3.1.2 factory: all outputs at 0
    hi = 0xFFFFFFFF if model.family is Family.DIGITAL_OUTPUTS else 0xFFFF
    for op in ("or", "and"):
        for word in ("blink", "state"):
            yield ParamSpec(
                f"fallback.{op}_{word}",
                0,
                f"{op.upper()} mask of output command word {word}",
                0,
                hi,
            )
    if model.family is Family.DIGITAL_INPUTS:
        yield ParamSpec(
            "outputs.command", 0, "output command word 1 at power-on (MP 00Dh)", 0, 0xFFFF
        )
    if model.safety:
        yield ParamSpec(
            "security_inputs", 0, "inputs wired in security mode (bit i = E(i+1))", 0, 0xFFFFFFFF
        )


def _analog(model: TesModel) -> Iterator[ParamSpec]:
    yield ParamSpec(
        "storage_period_s", 1, "history storage period, 0 = off (§6.4.13)", 0, 0xFFFF, unit="s"
    )
    yield ParamSpec("threshold_polarity", 0, "reversed reflex outputs (bit i = output i)", 0, 0xF)
    yield ParamSpec("fallback.digital_command", 0, "digital output command at fallback", 0, 0x0F0F)
    yield ParamSpec("ao.fallback_enable", 0, "analog outputs allowed to fall back (bit k)", 0, 0xFF)
    for k in model.analog_inputs:
        p = f"ai{k}."
        yield ParamSpec(p + "filter", 2, "average on N samples (§4.2.3)", choices=FILTER_SIZES)
        yield ParamSpec(p + "scale", "off", "scaling (§4.2.4)", choices=("off", "on"))
        yield ParamSpec(p + "scale_min", 0, "final value at 0 points", -32768, 32767)
        yield ParamSpec(p + "scale_max", POINTS_MAX, "final value at 1023 points", -32768, 32767)
        for end in ("zero", "full"):
            yield ParamSpec(
                p + f"corr_{end}", 0, f"correction at {end} scale (§4.2.5)",
                -CORRECTION_MAX, CORRECTION_MAX, unit="points",
            )  # fmt: skip
        yield ParamSpec(p + "threshold", "none", "threshold type (§4.2.6)", choices=THRESHOLD_TYPES)
        yield ParamSpec(p + "low", 0, "low threshold (final value)", -32768, 32767)
        yield ParamSpec(p + "high", POINTS_MAX, "high threshold (final value)", -32768, 32767)
        yield ParamSpec(p + "out_low", NO_OUTPUT, "output of the low threshold, -1 = none", -1, 3)
        yield ParamSpec(p + "out_high", NO_OUTPUT, "output of the high threshold, -1 = none", -1, 3)
    for k in model.analog_outputs:
        p = f"ao{k}."
        yield ParamSpec(p + "scale", "off", "scaling (§4.3.1)", choices=("off", "on"))
        yield ParamSpec(p + "scale_min", 0, "user value at 0 V / 0 mA", -32768, 32767)
        yield ParamSpec(p + "scale_max", DAC_MAX, "user value at full scale", -32768, 32767)
        yield ParamSpec(p + "fallback", 0, "fallback value (§4.3.2)", -32768, 32767)


@functools.cache
def param_specs(model: TesModel) -> Mapping[str, ParamSpec]:
    """Every EEPROM parameter of ``model``, in TESIS screen order (built once per model)."""
    specs = [*_link("rs485", 38400), *_link("rs232", 9600), *_digital(model)]
    specs += list(_analog(model) if model.is_analog else _masks(model))
    return MappingProxyType({s.name: s for s in specs})


def factory(model: TesModel) -> dict[str, Value]:
    """§3.1.2: the settings the Prm jumper gives."""
    return {name: spec.factory for name, spec in param_specs(model).items()}


def parse_value(model: TesModel, name: str, raw: object) -> Value:
    specs = param_specs(model)
    spec = specs.get(name)
    if spec is None:
        raise ConfigError(f"{model.name} has no parameter {name!r} (see `tesis show`)")
    return spec.parse(raw)


def complete(model: TesModel, values: Mapping[str, object]) -> dict[str, Value]:
    """Factory values overlaid with ``values`` (each checked)."""
    out = factory(model)
    for name, raw in values.items():
        out[name] = parse_value(model, name, raw)
    return out
