"""The checked tree of a PL7-3 program: frozen slotted dataclasses.

Positions (``pos``) are kept for messages but take no part in equality, so a
program printed and parsed again compares equal to the original tree.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from fieldtwin.objects import ObjectRef


@dataclass(frozen=True, slots=True)
class Pos:
    line: int = 0
    column: int = 0

    def __str__(self) -> str:
        return f"line {self.line}, column {self.column}"


NOWHERE = Pos()

# --- objects -----------------------------------------------------------------------

BIT_KINDS = ("B", "SY", "X", "XM")  # internal, system and step bits
WORD_KINDS = ("W", "CW", "SW")  # internal, constant and system words
TXT_WORD_FIELDS = ("M", "C", "L", "V", "R", "S")  # AEM 4.2-1, SCM 3.3
TXT_BIT_FIELDS = ("D", "E")
TXT_WRITABLE = ("M", "C", "L")


@dataclass(frozen=True, slots=True)
class Internal:
    """``B12``, ``W20``, ``CW100``, ``SY0``, ``SW51``, ``X3`` (a step), ``XM0`` (a macro-step)."""

    kind: str
    index: int
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)

    @property
    def is_bit(self) -> bool:
        return self.kind in BIT_KINDS


@dataclass(frozen=True, slots=True)
class InternalBit:
    """Bit j of an internal or system word: ``W131,A``."""

    word: Internal
    bit: int


@dataclass(frozen=True, slots=True)
class ModuleObj:
    """``IW5,2,D``, ``OW4,1``, ``I14,0``, ``O16,C``, ``I5,S`` (fieldtwin.objects)."""

    ref: ObjectRef


@dataclass(frozen=True, slots=True)
class TxtField:
    """``TXT0,M`` .. ``TXT0,E`` (``Txt_1,D`` is the same object as ``TXT1,D``)."""

    index: int
    name: str
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)

    @property
    def is_bit(self) -> bool:
        return self.name in TXT_BIT_FIELDS


@dataclass(frozen=True, slots=True)
class Table:
    """A bit string ``B1[8]`` / ``I5,0[4]`` or a word table ``W2510[2]`` / ``CW0[34]``."""

    start: Internal | ModuleObj
    length: int
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Indexed:
    """``W0(W124)``: the word W[0 + W124]."""

    base: Internal
    index: Internal
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


# --- expressions -------------------------------------------------------------------


class Radix(enum.Enum):
    DEC = "D"
    HEX = "H"
    B = "B"  # B'0802' read as hex digits (AMB-SCM-01)
    TEXT = "M"  # M'on': two characters, the first in the low byte (DEM 5.3-4)


@dataclass(frozen=True, slots=True)
class Const:
    value: int
    radix: Radix = Radix.DEC


class Op(enum.Enum):
    """Binary operators; ``symbol`` is how the source writes them."""

    OR = ("+", 1, "bit")
    AND = (".", 2, "bit")
    ADD = ("+", 1, "word")
    SUB = ("-", 1, "word")
    WOR = ("OR", 1, "word")
    WXOR = ("XOR", 1, "word")
    MUL = ("*", 2, "word")
    DIV = ("/", 2, "word")
    REM = ("REM", 2, "word")
    WAND = ("AND", 2, "word")

    @property
    def symbol(self) -> str:
        return self.value[0]

    @property
    def level(self) -> int:
        return self.value[1]

    @property
    def on_bits(self) -> bool:
        return self.value[2] == "bit"


@dataclass(frozen=True, slots=True)
class Binary:
    op: Op
    left: Expr
    right: Expr


@dataclass(frozen=True, slots=True)
class Not:
    operand: Expr


@dataclass(frozen=True, slots=True)
class Edge:
    """``RE(I2,B)`` (rising) / ``FE(B3)`` (falling) of a bit object."""

    rising: bool
    operand: Bit


@dataclass(frozen=True, slots=True)
class Compare:
    """``[IW5,1<>0]``; ``op`` is one of = <> < > <= >=."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True, slots=True)
class Shift:
    """``SHL 8(SW54)`` / ``SHR 8(IW5,1)``."""

    left: bool
    count: int
    operand: Expr


@dataclass(frozen=True, slots=True)
class Bta:
    """``BTA(W150)``: a word in 6 ASCII characters (3 words), DEM 5.3-4 SR0."""

    operand: Expr


Bit = Internal | InternalBit | ModuleObj | TxtField
Expr = (
    Internal
    | InternalBit
    | ModuleObj
    | TxtField
    | Table
    | Indexed
    | Const
    | Binary
    | Not
    | Edge
    | Compare
    | Shift
    | Bta
)

COMPARE_OPS = ("=", "<>", "<=", ">=", "<", ">")

# --- statements --------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Assign:
    """``0->W23->W24->W25``: the source, then every target in order."""

    source: Expr
    targets: tuple[Expr, ...]


@dataclass(frozen=True, slots=True)
class SetBit:
    target: Expr
    value: bool  # SET (True) / RESET (False)


@dataclass(frozen=True, slots=True)
class TxtOp:
    """``EXCHG TXT0``, ``INPUT TXT3``, ``OUTPUT TXT3``, ``RESET TXT0``."""

    op: str
    index: int
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Step:
    """``INC W121`` (up) / ``DEC W5`` (down)."""

    up: bool
    target: Expr


@dataclass(frozen=True, slots=True)
class Jump:
    label: int
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Call:
    sr: int
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Ret:
    pass


Action = Assign | SetBit | TxtOp | Step | Jump | Call | Ret


@dataclass(frozen=True, slots=True)
class If:
    condition: Expr
    then: tuple[Action, ...]
    otherwise: tuple[Action, ...] | None = None


@dataclass(frozen=True, slots=True)
class While:
    condition: Expr
    body: tuple[Action, ...]


Statement = Action | If | While


@dataclass(frozen=True, slots=True)
class Comment:
    """A ``<...`` line, kept so that a program prints back as it was written."""

    text: str


@dataclass(frozen=True, slots=True)
class Sentence:
    """``!L3 :IF B2 THEN CALL SR1``: an optional label and its instructions."""

    label: int | None
    body: tuple[Statement, ...]
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


# --- sections ----------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Literal:
    """A Literal module: ``PRE``, ``POST`` or ``SRi``."""

    name: str
    sentences: tuple[Sentence | Comment, ...]
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


MAIN = -1  # the main chart; a macro-step expansion XMj is chart j


@dataclass(frozen=True, slots=True)
class StepActions:
    """``CHART S(A)3`` / ``XM0 S(D) 3``: the sentences run when the step is activated
    (``A``) or deactivated (``D``).  Steps are ``"3"``, ``"M0"``, ``"IN"``, ``"OUT"``."""

    chart: int
    step: str
    kind: str
    sentences: tuple[Sentence | Comment, ...]
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Transition:
    """``T: 3>4`` with its condition ``I2,3.I2,4``."""

    chart: int
    source: str
    target: str
    condition: Expr
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Initial:
    """``CHART INITIAL M0``: the initial steps of the main chart."""

    steps: tuple[str, ...]
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


ChartItem = StepActions | Transition | Initial | Comment


@dataclass(frozen=True, slots=True)
class Chart:
    items: tuple[ChartItem, ...]
    pos: Pos = field(default=NOWHERE, compare=False, repr=False)


Section = Literal | Chart


@dataclass(frozen=True, slots=True)
class Program:
    sections: tuple[Section, ...]

    def section(self, name: str) -> Section | None:
        for section in self.sections:
            if (isinstance(section, Chart) and name == "CHART") or (
                isinstance(section, Literal) and section.name == name
            ):
                return section
        return None
