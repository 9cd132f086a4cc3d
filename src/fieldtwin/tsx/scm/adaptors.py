"""The discrete signals of each line adaptor (SCM 5.1).

Four output bits per channel (Oxy,0..3 channel 0, Oxy,4..7 channel 1) and four
input bits (Ixy,8..B channel 0, Ixy,C..F channel 1).  A signal is active at 0.
The order of the signals inside each group was in figures the scan lost
(AMB-SCM-25); the order chosen here is recorded in docs/manual-notes.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.scm.variants import Adaptor

# index in the channel's 4-bit group -> signal name
OUTPUTS: dict[Adaptor, tuple[str, ...]] = {
    Adaptor.SCA1: ("DTR",),
    Adaptor.SCA2: ("PSR",),
    Adaptor.SCA3: ("DTR", "DSRS"),
    Adaptor.SCA4: (),
    Adaptor.SCA5: (),
    Adaptor.NONE: (),
}
INPUTS: dict[Adaptor, tuple[str, ...]] = {
    Adaptor.SCA1: ("CTS", "CD"),
    Adaptor.SCA2: ("PSR",),  # SCM 5.1: "This bit is the image of output bit PSR"
    Adaptor.SCA3: ("CTS", "CD", "DSR", "RI"),
    Adaptor.SCA4: (),
    Adaptor.SCA5: (),
    Adaptor.NONE: (),
}
# SCM 5.1: SCA1 unwired CTS/CD are pulled to 0 (active); SCA3 unused signals pulled up to 1
UNWIRED_LEVEL = {Adaptor.SCA3: 1}
# SCM 5.1 SCA2 PSR: "0 = used in multipoint mode, 1 = used in point-to-point mode"
LOOP_PSR = {"multipoint": 0, "point-to-point": 1}


@dataclass(slots=True)
class Signals:
    """The control signals of one channel's adaptor."""

    adaptor: Adaptor
    inputs: dict[str, int] = field(default_factory=dict)
    outputs: int = 0  # the channel's 4 output bits as the program wrote them
    dtr_auto: int | None = None  # SCM 3.2 automatic DTR (full-duplex): the module drives it
    loop: str | None = None  # SCA2: how the current loop is wired (None: not modelled)

    def __post_init__(self) -> None:
        level = UNWIRED_LEVEL.get(self.adaptor, 0)
        self.inputs = {name: level for name in INPUTS[self.adaptor] if name != "PSR"}

    def set_input(self, name: str, level: int) -> None:
        key = name.strip().upper()
        if key not in self.inputs:
            allowed = ", ".join(self.inputs) or "none"
            raise ConfigError(
                f"{self.adaptor.label} has no settable input signal {name!r} (allowed: {allowed})"
            )
        if level not in (0, 1):
            raise ConfigError(f"signal {key} level {level!r} not allowed (allowed 0 or 1)")
        self.inputs[key] = level

    def output(self, name: str) -> int:
        names = OUTPUTS[self.adaptor]
        return (self.outputs >> names.index(name)) & 1 if name in names else 1

    @property
    def dtr(self) -> int:
        """The DTR line: the module's own level when automatic, else the program's bit."""
        return self.dtr_auto if self.dtr_auto is not None else self.output("DTR")

    @property
    def transmit_enabled(self) -> bool:
        # SCM 5.1: CTS at 1 (inactive) inhibits the transmission circuit (SCA1, SCA3)
        return self.inputs.get("CTS", 0) == 0

    @property
    def receive_enabled(self) -> bool:
        # SCM 5.1: CD at 1 (inactive) inhibits the reception circuit (SCA1, SCA3)
        return self.inputs.get("CD", 0) == 0

    @property
    def half_speed(self) -> bool:
        # SCM 5.1 SCA3 DSRS: 1 = the channel operates at half the configured speed
        return self.adaptor is Adaptor.SCA3 and self.output("DSRS") == 1

    def set_loop(self, loop: str) -> None:
        if self.adaptor is not Adaptor.SCA2:
            raise ConfigError(f"{self.adaptor.label}: only an SCA2 adaptor has a current loop")
        key = loop.strip().lower()
        if key not in LOOP_PSR:
            raise ConfigError(f"loop {loop!r} not allowed (allowed: {', '.join(LOOP_PSR)})")
        self.loop = key

    @property
    def rx_inverted(self) -> bool:
        # SCM 5.1 SCA2: "The state of this bit inverses the current loop reception circuit
        # logic": a PSR that does not match the wiring reads every level inverted
        return self.loop is not None and self.output("PSR") != LOOP_PSR[self.loop]

    def input_nibble(self) -> int:
        """The channel's 4 discrete input bits."""
        nibble = 0
        for index, name in enumerate(INPUTS[self.adaptor]):
            level = self.output("PSR") if name == "PSR" else self.inputs[name]
            nibble |= level << index
        return nibble

    def describe(self) -> str:
        parts = [f"{n}={v}" for n, v in self.inputs.items()]
        parts += [f"{n}={self.output(n)}" for n in OUTPUTS[self.adaptor] if n != "DTR"]
        if self.loop is not None:
            parts.append(f"loop {self.loop}" + (" (receiver inverted)" if self.rx_inverted else ""))
        if "DTR" in OUTPUTS[self.adaptor]:
            parts.append(f"DTR={self.dtr}" + (" (auto)" if self.dtr_auto is not None else ""))
        return " ".join(parts) or "no control signals"
