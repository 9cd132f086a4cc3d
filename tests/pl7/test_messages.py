"""A refused program names its file, line and column, and a near miss the keyword
(issue 24: PL7 messages)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.pl7.errors import Pl7Error
from fieldtwin.pl7.parser import parse
from fieldtwin.plant import load_plant


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("!     CAL SR1", "line 2, column 7: 'CAL': unknown instruction (did you mean CALL?)"),
        (
            "!     IF B1 THEN SE B2",
            "line 2, column 18: 'SE': unknown instruction (did you mean SET?)",
        ),
        ("!     WHIL B1 DO INC W1", "column 7: 'WHIL': unknown instruction (did you mean WHILE?)"),
        ("!     RESTE B2", "column 7: 'RESTE': unknown instruction (did you mean RESET?)"),
    ],
)
def test_a_near_miss_keyword_is_suggested(line: str, message: str) -> None:
    with pytest.raises(Pl7Error) as refused:
        parse(f"%PRE\n{line}\n", "x.pl7")
    assert str(refused.value).startswith("x.pl7: line 2, column ")
    assert message in str(refused.value)


def test_a_word_far_from_every_keyword_still_says_what_is_expected() -> None:
    with pytest.raises(Pl7Error, match=r"'QQQQ': expected an object"):
        parse("%PRE\n!     QQQQ->W1\n", "x.pl7")


def test_an_object_of_an_empty_slot_names_file_line_and_column(tmp_path: Path) -> None:
    (tmp_path / "p.pl7").write_text("%PRE\n!     30->W2\n!     IW6,0->W3\n")
    (tmp_path / "plant.toml").write_text('[plc]\nmodel = "TSX 87"\nprogram = "p.pl7"\n')
    with pytest.raises(ConfigError) as refused:
        load_plant(tmp_path / "plant.toml")
    text = str(refused.value)
    assert f"{tmp_path / 'p.pl7'}: line 3, column 7: 'IW6,0'" in text
    assert "no module in rack 0 slot 6" in text
