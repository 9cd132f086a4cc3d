"""The ten TES models and what each one carries.

The manual (P DOC TES 002 E) gives the I/O counts only through the memory
map (§6.2.4 labels "TES 16 EST ... input No 7"); the readings are recorded in
docs/manual-notes.md (AMB-TES-13).
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from fieldtwin.errors import ConfigError


class Family(enum.Enum):
    """Which memory map of section 6 a model uses."""

    DIGITAL_INPUTS = "6.2"  # 16 EST, 32 EST, 32 ET, 32 ET-S
    DIGITAL_OUTPUTS = "6.3"  # 32 ST
    ANALOG = "6.4"  # 4EA, 4SA, 8EA, 8ESA, 8SA-U


@dataclass(frozen=True, slots=True)
class ElectricalRange:
    """An analog channel's electrical span (§4.3.1: 0..10 V or 0..20 mA)."""

    unit: str
    full_scale: float

    def describe(self) -> str:
        return f"0..{self.full_scale:g} {self.unit}"


VOLTS = ElectricalRange("V", 10.0)
MILLIAMPS = ElectricalRange("mA", 20.0)


@dataclass(frozen=True, slots=True)
class TesModel:
    """One model: name, map family and channel counts."""

    name: str
    family: Family
    digital_inputs: int
    digital_outputs: int
    analog_inputs: tuple[int, ...] = ()  # analog channel numbers that are inputs
    analog_outputs: tuple[int, ...] = ()  # analog channel numbers that are outputs
    safety: bool = False  # TES 32ET-S wiring supervision (§4.1.5)
    analog_range: ElectricalRange = VOLTS

    @property
    def analog_slots(self) -> int:
        """Acquisition round length (§4.2.1: 32 ms on 4 channels, 64 ms on 8)."""
        return 4 if len(self.analog_inputs) <= 4 else 8

    @property
    def is_analog(self) -> bool:
        return self.family is Family.ANALOG


_MODELS = (
    # §6.2.4: "TES 16 EST" labels input No 7, "TES 32 EST" No 15, "TES 32 ET" No 31.
    TesModel("TES 16EST", Family.DIGITAL_INPUTS, 8, 8),
    TesModel("TES 32EST", Family.DIGITAL_INPUTS, 16, 16),
    TesModel("TES 32ET", Family.DIGITAL_INPUTS, 32, 0),
    TesModel("TES 32ET-S", Family.DIGITAL_INPUTS, 32, 0, safety=True),
    # §6.3.2: outputs state [15..00] and [31..16].
    TesModel("TES 32ST", Family.DIGITAL_OUTPUTS, 0, 32),
    # §6.4.2 / 6.4.5: digital inputs [3..0] and outputs [3..0] on every analog model.
    TesModel("TES 4EA", Family.ANALOG, 4, 4, analog_inputs=(0, 1, 2, 3)),
    TesModel("TES 4SA", Family.ANALOG, 4, 4, analog_outputs=(0, 1, 2, 3)),
    TesModel("TES 8EA", Family.ANALOG, 4, 4, analog_inputs=tuple(range(8))),
    # §6.4.6 warning: the 4 analog outputs of a TES 8 ESA are Nos 4, 5, 6 and 7.
    TesModel(
        "TES 8ESA", Family.ANALOG, 4, 4, analog_inputs=(0, 1, 2, 3), analog_outputs=(4, 5, 6, 7)
    ),
    TesModel("TES 8SA-U", Family.ANALOG, 4, 4, analog_outputs=tuple(range(8))),
)

MODELS: dict[str, TesModel] = {m.name: m for m in _MODELS}


def _key(text: str) -> str:
    return re.sub(r"[\s_]", "", text.upper()).removeprefix("TES")


_BY_KEY = {_key(name): model for name, model in MODELS.items()}


def model_named(name: str) -> TesModel:
    """``"TES 8EA"``, ``"8EA"`` or ``"tes 16 est"`` -> the model; ConfigError otherwise."""
    model = _BY_KEY.get(_key(str(name)))
    if model is None:
        raise ConfigError(f"unknown TES model {name!r} (allowed: {', '.join(MODELS)})")
    return model
