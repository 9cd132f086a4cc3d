"""docs/scenarios.md tells the truth: its scenario blocks read and pass on the default
plant, its two complete examples are the files of examples/scenarios/ (their console
transcripts are run by tests/test_docs.py), the error it quotes is the product's."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.scenario import parse_scenario
from fieldtwin.testing import run_scenario
from tests.test_docs import code_blocks

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "scenarios.md"
SCENARIOS = [
    b.text
    for b in code_blocks(PAGE)
    if b.lang == "toml" and {"step", "expect"} & set(tomllib.loads(b.text))
]


def test_the_page_shows_both_examples_whole() -> None:
    for name in ("fault_drill.toml", "scada_alarm.toml"):
        assert (ROOT / "examples" / "scenarios" / name).read_text() in SCENARIOS


@pytest.mark.parametrize("text", SCENARIOS, ids=[f"block{i}" for i in range(len(SCENARIOS))])
def test_every_scenario_block_passes_on_the_default_plant(text: str, tmp_path: Path) -> None:
    path = tmp_path / "block.toml"
    path.write_text(text)
    assert run_scenario(load_plant(None), path)["passed"]


def test_the_quoted_error_is_the_products() -> None:
    with pytest.raises(ConfigError) as error:
        parse_scenario(
            "[[step]]\nat_s = 1\npower_off = { device = 'tes2', seconds = 9999 }", "bad.toml"
        )
    assert f"fieldtwin: {error.value}" in PAGE.read_text()
