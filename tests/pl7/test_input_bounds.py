"""PL7 program text is bounded in size and depth (issue 20 R8/R9; docs/pl7.md "Bounds").

A deep expression is refused with its line and column, never a RecursionError; a
program file is a regular file of UTF-8, read with a bound.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.pl7 import Pl7Error, parse
from fieldtwin.pl7.expressions import MAX_DEPTH
from fieldtwin.plant import load_plant
from fieldtwin.tsx.plc import Plc

DEEP = f"an expression nested at most {MAX_DEPTH} deep"


@pytest.mark.parametrize(
    ("text", "column"),
    [
        ("!IF " + "(" * 5000 + "B0" + ")" * 5000 + " THEN SET B1\n", 5 + MAX_DEPTH),
        ("!IF " + "NOT " * 100_000 + "B0 THEN SET B1\n", 5 + 4 * MAX_DEPTH),
        ("!" + "+".join(["B0"] * 100_000) + " -> B1\n", 2 + 3 * (MAX_DEPTH + 1) - 1),
        ("!" + "*".join(["W0"] * 5000) + " -> W1\n", 2 + 3 * (MAX_DEPTH + 1) - 1),
        ("!IF " + "[" * 3000 + "W0" + "=0]" * 3000 + " THEN SET B1\n", 5 + MAX_DEPTH),
    ],
    ids=["parentheses", "nots", "or-chain", "mul-chain", "brackets"],
)
def test_a_deep_expression_is_refused_with_line_and_column(text: str, column: int) -> None:
    with pytest.raises(Pl7Error) as info:
        Plc(speed=None).load_program("< deep\n" + text, source="deep.pl7")
    err = info.value
    assert (err.line, err.column) == (2, column)
    assert str(err).startswith(f"deep.pl7: line 2, column {column}: ")
    assert DEEP in str(err)


def test_depth_up_to_the_bound_compiles_and_runs() -> None:
    plc = Plc(speed=None)
    plc.load_program(
        "!IF " + "(" * (MAX_DEPTH - 1) + "NOT B0" + ")" * (MAX_DEPTH - 1) + " THEN SET B1\n"
        "!" + "*".join(["W2"] * MAX_DEPTH) + " -> W3\n"
        "!" + "+".join(["W4"] * MAX_DEPTH) + " -> W5\n"
        "!" + " + ".join(f"B{10 + k}" for k in range(MAX_DEPTH)) + " -> B6\n"
    )
    plc.write("W2", 0xFFFF)  # -1: (-1)**64 = 1
    plc.write("W4", 3)
    plc.write("B73", 1)
    plc.advance(0.01)
    assert plc.read("B1") == 1 and plc.read("W3") == 1 and plc.read("W5") == 3 * MAX_DEPTH
    assert plc.read("B6") == 1
    plc.write("W2", 0xFFFE)  # -2: (-2)**64 modulo 2**16 is 0
    plc.write("W4", 0x8000)
    plc.advance(0.01)
    assert plc.read("W3") == 0 and plc.read("W5") == 0


def test_the_same_bound_in_a_transition() -> None:
    text = "%CHART\nCHART INITIAL 1\nT: 1>2\n!" + "NOT " * 200 + "B0\n"
    with pytest.raises(Pl7Error, match=DEEP) as info:
        parse(text)
    assert info.value.line == 4


def _plant(tmp_path: Path, program: str) -> Path:
    path = tmp_path / "plant.toml"
    path.write_text(f'[plc]\nprogram = "{program}"\n')
    return path


def test_a_deep_program_in_a_plant_file_names_the_file(tmp_path: Path) -> None:
    (tmp_path / "deep.pl7").write_text("!IF " + "(" * 5000 + "B0" + ")" * 5000 + " THEN SET B1\n")
    with pytest.raises(ConfigError) as info:
        load_plant(_plant(tmp_path, "deep.pl7"))
    message = str(info.value)
    assert "plc.program: " in message and "deep.pl7: line 1, column 69" in message
    assert DEEP in message


@pytest.mark.parametrize(
    ("program", "said"),
    [("/dev/zero", "a character device, not a regular file"), ("fifo.pl7", "a FIFO")],
)
def test_a_program_that_is_not_a_regular_file_is_refused(
    tmp_path: Path, program: str, said: str
) -> None:
    os.mkfifo(tmp_path / "fifo.pl7")  # nobody writes: reading it would block
    with pytest.raises(ConfigError) as info:
        load_plant(_plant(tmp_path, program))
    message = str(info.value)
    assert said in message and "allowed: a regular PL7 program of at most 1 MiB, UTF-8" in message


def test_a_non_utf8_program_is_reported_as_such(tmp_path: Path) -> None:
    (tmp_path / "latin.pl7").write_bytes(b"< caf\xe9\n!SET B0\n")
    with pytest.raises(ConfigError) as info:
        load_plant(_plant(tmp_path, "latin.pl7"))
    message = str(info.value)
    assert "latin.pl7:1: not a UTF-8 text file" in message
    assert "not a file name" not in message


def test_a_program_file_larger_than_the_bound_is_refused(tmp_path: Path) -> None:
    (tmp_path / "big.pl7").write_text("!SET B0\n" * 140_000)  # 1.1 MB
    with pytest.raises(ConfigError, match=r"big\.pl7: larger than 1 MiB"):
        load_plant(_plant(tmp_path, "big.pl7"))
    with pytest.raises(ConfigError, match=r"big\.pl7: larger than 1 MiB"):
        Plc(speed=None).load_program(tmp_path / "big.pl7")


def test_a_deep_program_through_the_api_console_is_an_error_not_a_500(tmp_path: Path) -> None:
    from fieldtwin.control.resources import Control
    from fieldtwin.runtime.runner import Runner
    from tests.control.plantproc import default_plant_copy

    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    try:
        control = Control(plant, Runner(plant.clock, None), plant.events)
        for text in ("!IF " + "(" * 5000 + "B0" + ")" * 5000 + " THEN SET B1\n",
                     "!IF " + "NOT " * 100_000 + "B0 THEN SET B1\n"):  # fmt: skip
            answer = control.console_line("prog load -", text)
            assert answer["lines"] == [], answer
            assert str(answer["error"]).startswith("<text>: line 1, column "), answer
            assert DEEP in str(answer["error"])
        assert control.plant_json()["plc"] == {"mode": "RUN", "fault": None}
    finally:
        plant.close()
