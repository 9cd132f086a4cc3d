"""The console commands and their stable output formats (docs/console.md)."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

import tests.tsx.double  # noqa: F401  registers the test double
from fieldtwin.console import Console, parse_duration, run_script
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from tests.tsx.double import DOUBLE


@pytest.fixture
def console(tmp_path: Path) -> Console:
    path = tmp_path / "plant.toml"
    path.write_text(f"[plc]\nmodel = 'TSX 87'\n[[module]]\ntype = '{DOUBLE}'\nslot = 5\n")
    return Console(load_plant(path))


def test_read_write_and_time(console: Console) -> None:
    assert console.execute("advance 2.1") == ["t = 2.100 s"]
    assert console.execute("write OW5,0,C 1") == ["OW5,0,C = 1"]
    console.execute("advance 20ms")
    assert console.execute("IW5,0") == ["IW5,0 = H'1008'"]
    assert console.execute("read IW05,0,C I5,S") == ["IW5,0,C = 1", "I5,S = 0"]
    assert console.execute("OW5,1 = H'00FF'") == ["OW5,1 = H'00FF'"]
    assert console.execute("write W100 30") == ["W100 = 30"]
    assert console.execute("time") == ["t = 2.120 s"]
    assert console.execute("# a comment") == []


def test_exchange_output(console: Console) -> None:
    console.execute("advance 2.1")
    out = console.execute("exchange H'0563' H'49' text \"TANK\"")
    assert out == ["TXT0,V = H'00FE'  TXT0,S = 0  TXT0,E = 0"]
    out = console.execute("exchange H'0563' H'4A' recv 20 txt 3")
    assert out[0] == "TXT3,V = H'007A'  TXT3,S = 20  TXT3,E = 0"
    assert out[1].startswith("data = H'4154' H'4B4E'")
    assert out[2] == "text = 'TANK                '"
    bad = console.execute("exchange H'0663' H'0F' recv 27")
    assert bad == [
        "TXT0,V = H'0000'  TXT0,S = 5  TXT0,E = 1  (parameter error or too many active Text Blocks)"
    ]


def test_status_faults_power_and_modules(console: Console) -> None:
    console.execute("advance 2.1")
    assert console.execute("faults 5") == [
        "terminal_block: terminal block removed",
        "sensor: sensor wire cut",
    ]
    assert console.execute("fault 5 sensor on") == ["fault 5 sensor on"]
    console.execute("advance 20ms")
    status = console.execute("status 5")
    assert "leds: OK=on ERR=on F=off" in status
    assert any(line.startswith("IW: H'") for line in status)
    assert console.execute("remove 5") == ["module rack 0 slot 5 removed"]
    console.execute("advance 20ms")
    assert console.execute("I5,S") == ["I5,S = 1"]
    assert console.execute("insert 5") == ["module rack 0 slot 5 inserted"]
    assert console.execute("power break 1") == ["power back  t = 3.140 s"]
    assert console.execute("plc stop") == ["PLC STOP"]
    assert console.execute("input 5 2 1") == ["input 5 2 = 1"]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("frobnicate", "unknown command 'frobnicate' (allowed: read, write"),
        ("read QW5,0", "'QW5,0'"),
        ("write IW5,0 1", "is an input"),
        ("advance soon", "'soon' is not a duration"),
        ("fault 5 smoke on", "unknown fault 'smoke'"),
        ("status 7", "no module in rack 0 slot 7"),
        ("exchange H'0563'", "exchange: takes M C"),
        ("exchange H'0563' H'40' recv", "'recv' needs a value"),
        ("plc nap", "'nap' not allowed (allowed: run, stop, cold, hot)"),
        ("tes 3 read 0", "no TES with slave number 3"),
        ("help nothing", "unknown command 'nothing'"),
    ],
)
def test_errors_name_the_token(console: Console, line: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        console.execute(line)
    assert message in str(info.value)


def test_a_script_stops_at_the_first_error_with_status_2(console: Console) -> None:
    out, err = io.StringIO(), io.StringIO()
    status = run_script(console, ["advance 1", "read IW5,9", "advance 1"], out, err, "s.txt")
    assert status == 2
    assert out.getvalue() == "t = 1.000 s\n"
    assert err.getvalue().startswith("s.txt:2: read IW5,9: 'IW5,9'")


def test_quit_ends_a_script(console: Console) -> None:
    out, err = io.StringIO(), io.StringIO()
    assert run_script(console, ["advance 1", "quit", "read IW5,9"], out, err, "s.txt") == 0
    assert out.getvalue() == "t = 1.000 s\n" and err.getvalue() == ""


def test_durations() -> None:
    assert parse_duration("250ms") == 0.25
    assert parse_duration("2min") == 120
    assert parse_duration("1.5s") == 1.5
    assert parse_duration("3") == 3
    with pytest.raises(ConfigError):
        parse_duration("-1")
