"""Scenario files read and checked: every mistake names the file, the table and the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.scenario import MAX_ENTRIES, parse_scenario, read_scenario
from fieldtwin.scenario.spec import MAX_FILE_BYTES

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


def test_the_examples_read() -> None:
    drill = read_scenario(EXAMPLES / "fault_drill.toml")
    assert drill.title.startswith("Fault drill")
    assert [s.action for s in drill.steps] == ["fault", "power_off", "fault"]
    assert drill.end_s == 40
    assert drill.steps[1].text() == "power_off tes2 5 s"
    scada = read_scenario(EXAMPLES / "scada_alarm.toml")
    assert {e.kind for e in scada.expects} == {"register", "input", "led"}


def test_steps_and_expects_are_in_time_order_file_order_at_one_time() -> None:
    found = parse_scenario(
        """
[[step]]
at_s = 5
console = "plc stop"
[[step]]
at_s = 1
remove = { module = 14 }
[[step]]
at_s = 5
insert = { module = "14" }
[[expect]]
at_s = 2
object = "W0"
equals = 0
"""
    )
    assert [(s.index, s.at_s) for s in found.steps] == [(2, 1.0), (1, 5.0), (3, 5.0)]
    assert found.steps[0].args == {"module": "14"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "[[step]]\ninput = { device = '5', name = '0', value = 1 }",
            r"s\.toml: step\[1\]: at_s missing",
        ),
        ("[[step]]\nat_s = -1\nconsole = 'x'", r"step\[1\]\.at_s: -1 not allowed \(allowed: 0 to"),
        ("[[step]]\nat_s = 1e9\nconsole = 'x'", r"step\[1\]\.at_s: 1000000000.0 not allowed"),
        ("[[step]]\nat_s = 1", r"step\[1\]: no action \(allowed: exactly one of input, signal"),
        (
            "[[step]]\nat_s = 1\nconsole = 'a'\nremove = { module = '5' }",
            r"step\[1\]: actions console, remove \(allowed: exactly one",
        ),
        ("[[step]]\nat_s = 1\nexplode = 1", r"step\[1\]: unknown key\(s\) explode \(allowed: at_s"),
        (
            "[[step]]\nat_s = 1\nfault = { device = '5' }",
            r"step\[1\]\.fault: name missing \(takes device, name, \[active\], \[params\]\)",
        ),
        (
            "[[step]]\nat_s = 1\nfault = { device = '5', name = 'x', active = 'yes' }",
            r"step\[1\]\.fault\.active: 'yes' not allowed \(allowed: true, false\)",
        ),
        (
            "[[step]]\nat_s = 1\npower_off = { device = 'tes1', seconds = 4000 }",
            r"step\[1\]\.power_off\.seconds: 4000 not allowed \(allowed: 0 to 3600\)",
        ),
        (
            "[[step]]\nat_s = 1\nwrite = { object = 'W0', device = 'tes1', value = 1 }",
            r"step\[1\]\.write: give either object .* or device and register",
        ),
        (
            "[[step]]\nat_s = 1\nwrite = { object = 'W0', value = 70000 }",
            r"step\[1\]\.write\.value: 70000 not allowed \(allowed: a word",
        ),
        ("[[expect]]\nat_s = 1\nequals = 1", r"expect\[1\]: give one of tag, object, or device"),
        (
            "[[expect]]\nat_s = 1\ndevice = 'tes1'\nequals = 1",
            r"expect\[1\]: with device, give one of input, output, register, led",
        ),
        ("[[expect]]\nat_s = 1\nobject = 'W0'", r"expect\[1\]: give either equals or between"),
        (
            "[[expect]]\nat_s = 1\nobject = 'W0'\nbetween = [5, 1]",
            r"expect\[1\]\.between: low 5 above high 1",
        ),
        (
            "[[expect]]\nat_s = 1\ndevice = '5'\nled = 'ERR'\nequals = 1",
            r"expect\[1\]\.equals: an LED's state",
        ),
        ("[[expect]]\nat_s = 1\nobject = 'W0'\nequals = 1\nwithin = 2", r"unknown key\(s\) within"),
        ("title = 3\n[[step]]\nat_s = 1\nconsole = 'x'", r"s\.toml: title: a string"),
        ("steps = []", r"s\.toml: unknown key\(s\) steps \(allowed: title, description"),
        ("title = 'nothing'", r"no \[\[step\]\] and no \[\[expect\]\] table"),
        ("[[step]\nat_s = 1", r"s\.toml: not valid TOML"),
    ],
)
def test_a_mistake_names_the_file_table_and_field(text: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_scenario(text, "s.toml")


def test_bounded_tables_and_file(tmp_path: Path) -> None:
    many = "".join(f"[[step]]\nat_s = {i}\nconsole = 'time'\n" for i in range(MAX_ENTRIES + 1))
    with pytest.raises(
        ConfigError, match=rf"{MAX_ENTRIES + 1} \[\[step\]\] and \[\[expect\]\] tables"
    ):
        parse_scenario(many, "s.toml")
    big = tmp_path / "big.toml"
    big.write_text("#" * (MAX_FILE_BYTES + 1))
    with pytest.raises(ConfigError, match=r"big\.toml: larger than 1000000 bytes"):
        read_scenario(big)
    with pytest.raises(ConfigError, match=r"missing\.toml: cannot read the scenario file"):
        read_scenario(tmp_path / "missing.toml")
