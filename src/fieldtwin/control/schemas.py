"""The request bodies of the control API: validated, closed (no unknown field), bounded.

Every field states what is allowed; FastAPI answers a body that does not fit
with a 422 naming the field (fieldtwin.control.errors).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from fieldtwin.runtime.pace import MAX_SPEED, MIN_SPEED


def _no_bool_no_text(value: object) -> object:
    """A JSON integer (``7`` or ``7.0``, as JSON Schema's integer), never ``true`` nor ``"7"``."""
    if isinstance(value, bool | str):
        raise ValueError("Input should be a valid integer (not a boolean nor a string)")
    return value


NoBool = BeforeValidator(_no_bool_no_text)
Word = Annotated[
    int, Field(strict=False, ge=0, le=0xFFFF, description="a 16-bit word, 0..65535"), NoBool
]
Number = Annotated[float, Field(allow_inf_nan=False)]
Name = Annotated[str, Field(min_length=1, max_length=64)]
MAX_SIGNAL_KEYS = 32
MAX_SEND_WORDS = 128  # a Text Block's send table (the AEM's longest request is far below)
MAX_TEXT = 1024  # bytes of text a Text Block sends
MAX_LINE = 4096  # characters of one console line
MAX_PROGRAM_TEXT = 48 * 1024  # characters of a program's text sent with `prog load -`


class Closed(BaseModel):
    """Strict: a JSON value is taken as its own type only (``false`` is no number,
    ``"1"`` no integer); an integer is a number where a number is asked."""

    model_config = ConfigDict(extra="forbid", strict=True)


class InputBody(Closed):
    """Either ``value`` (in the input's unit, as the console takes it) or ``signal``
    (a signal table exactly as the plant file writes it: ``{"kind": "sine", ...}``;
    an integer stays one, as a ``seed`` must be)."""

    value: bool | int | float | Annotated[str, Field(max_length=64)] | None = None
    signal: (
        dict[Name, bool | int | float | Annotated[str, Field(max_length=256)] | list[object]] | None
    ) = Field(default=None, max_length=MAX_SIGNAL_KEYS)


class FaultBody(Closed):
    active: bool = True
    params: dict[Name, Number] = Field(default_factory=dict, max_length=8)


class ObjectBody(Closed):
    value: Word


class ExchangeBody(Closed):
    m: Word = Field(description="TXTi,M: H'xyzz' rack x, slot y, channel zz (63: module system)")
    c: Annotated[int, Field(strict=False, ge=0, le=0xFF), NoBool] = Field(
        description="TXTi,C: the request code"
    )
    send: list[Word] = Field(default_factory=list, max_length=MAX_SEND_WORDS)
    text: Annotated[str, Field(max_length=MAX_TEXT)] | None = None
    length: Annotated[int, Field(strict=False, ge=0, le=MAX_TEXT), NoBool] | None = None
    recv: Annotated[int, Field(strict=False, ge=0, le=2 * MAX_SEND_WORDS), NoBool] = 0
    txt: Annotated[int, Field(strict=False, ge=0, le=63), NoBool] = (
        0  # TXT0..TXT63 (AEM 3.5-1: N/MAX 64)
    )


MAX_MODE_WAIT_S = 3600.0  # the longest a request may wait for its mode's end


class ModeBody(Closed):
    """A command that starts a runner mode answers at once; with ``wait`` it answers at
    the mode's end, or after ``wait_s`` wall seconds with the mode still running."""

    wait: bool = Field(default=False, description="answer at the mode's end (bounded)")
    wait_s: Annotated[float, Field(gt=0, le=MAX_MODE_WAIT_S, allow_inf_nan=False)] = Field(
        default=60.0, description="with wait: the longest wait, wall seconds"
    )


class PowerBreakBody(ModeBody):
    seconds: Annotated[float, Field(ge=0, le=3600, allow_inf_nan=False)]


class PowerCycleBody(Closed):
    """A TES's outage: off now, on again ``seconds`` later (0: at once)."""

    seconds: Annotated[float, Field(ge=0, le=3600, allow_inf_nan=False)] = 0.0


class ModuleBody(Closed):
    module: Annotated[str, Field(pattern=r"^\d{1,2}$", description="5 (rack 0) or 23")]


class StepBody(ModeBody):
    ms: Annotated[float, Field(gt=0, le=86_400_000, allow_inf_nan=False)]


class RunUntilBody(ModeBody):
    t_s: Annotated[float, Field(ge=0, le=1e9, allow_inf_nan=False)]


class SpeedBody(Closed):
    speed: (
        Annotated[
            float,
            Field(
                ge=MIN_SPEED,
                le=MAX_SPEED,
                allow_inf_nan=False,
                description=f"a factor from {MIN_SPEED:g} to {MAX_SPEED:g}",
            ),
        ]
        | Literal["max"]
    )


class ConsoleBody(Closed):
    line: Annotated[str, Field(max_length=MAX_LINE)]
    text: Annotated[str, Field(max_length=MAX_PROGRAM_TEXT)] | None = Field(
        default=None,
        description="the text that comes with the line: a program's, for `prog load -`"
        " (no request names a file)",
    )
    wait_s: Annotated[float, Field(gt=0, le=3600, allow_inf_nan=False)] = 60.0
