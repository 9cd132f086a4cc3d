"""The console commands and their stable output formats (docs/console.md)."""

from __future__ import annotations

import io
import re
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tests.tsx.double  # noqa: F401  registers the test double
from fieldtwin.console import HELP, Console, parse_duration, run_script
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.tsx.txt import ExchangeTimeout
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


def test_new_errors_are_config_errors(console: Console) -> None:
    # these escaped as ValueError / OverflowError / UnicodeEncodeError / AttributeError
    for line, message in [
        ("exchange 1 2 txt x", "exchange txt: 'x' is not an integer"),
        ("exchange 1 2 length x", "exchange length: 'x' is not an integer"),
        ("advance nan", "'nan' is not a duration"),
        ("advance 1e400", "'1e400' is not a duration"),
        ('exchange 1 2 text "\u20ac"', "'\u20ac' is not a character the module takes"),
        ("signal 5 0 step at_s=1 before=0 after=1", "takes no input signals"),
        ("exchange 1 2 recv -5", "reception capacity -5 not allowed"),
        ("txt x", "txt: 'x' is not an integer"),
    ]:
        with pytest.raises(ConfigError, match=re.escape(message)):
            console.execute(line)


def test_txt_shows_and_resets_a_text_block(console: Console) -> None:
    console.execute("advance 2.1")
    with pytest.raises(ExchangeTimeout, match="'txt 2 reset' ends it"):
        console.execute("exchange H'0563' 2 txt 2 timeout 0.1")  # the double holds code 2
    assert console.execute("txt 2") == ["TXT2: in module"]
    assert console.execute("txt 2 reset") == [
        "TXT2,V = H'0000'  TXT2,S = 1  TXT2,E = 1  (exchange in progress cancelled by reset)"
    ]
    assert console.execute("exchange H'0563' H'0F' recv 27 txt 2")[0].startswith("TXT2,V = H'003F'")
    assert console.execute("txt 2")[0] == "TXT2,V = H'003F'  TXT2,S = 27  TXT2,E = 0"


_TOKENS = st.sampled_from(
    [
        *HELP,
        "5",
        "0",
        "1",
        "15",
        "27",
        "-1",
        "x",
        "nan",
        "1e400",
        "H'0563'",
        "H'0F'",
        "0x47",
        "IW5,0",
        "OW5,0,C",
        "I5,S",
        "O5,0",
        "W100",
        "W99999",
        "=",
        "send",
        "text",
        "recv",
        "txt",
        "timeout",
        "length",
        "reset",
        "on",
        "off",
        "break",
        "sensor",
        "sine",
        "k=v",
        '"',
        '"A B"',
        "#",
        "250ms",
        "H'",
        "IW5,9",
        "QW5,0",
    ]
)


@settings(max_examples=300)
@given(st.one_of(st.lists(_TOKENS, max_size=7).map(" ".join), st.text(max_size=30)))
def test_any_line_gives_output_or_a_config_error(line: str) -> None:
    console = _console_for_properties()
    try:
        out = console.execute(line)
    except (ConfigError, ExchangeTimeout):
        return
    assert isinstance(out, list) and all(isinstance(text, str) for text in out)


_CONSOLE: list[Console] = []


def _console_for_properties() -> Console:
    """One plant for every example (a fresh one would make the test slow)."""
    if not _CONSOLE:
        path = Path(tempfile.mkdtemp()) / "plant.toml"
        path.write_text(f"[plc]\nmodel = 'TSX 87'\n[[module]]\ntype = '{DOUBLE}'\nslot = 5\n")
        _CONSOLE.append(Console(load_plant(path)))
    return _CONSOLE[0]


def test_tes_digital_input_takes_0_and_1(tmp_path: Path) -> None:
    path = tmp_path / "tes.toml"
    path.write_text('[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:0"\n')
    console = Console(load_plant(path))
    assert console.execute("tes 1 input 3 1") == ["tes 1 input 3 = 1"]
    assert console.execute("tes 1 input 3 false") == ["tes 1 input 3 = false"]
    status = console.execute("status")
    assert status[0] == "t = 0.000 s"
    assert status[1].startswith("TES 1 TES 32EST: on  status H'")


def test_an_interrupted_advance_stops_between_two_steps(tmp_path: Path) -> None:
    # issue 10 item 20: the terminal's Ctrl-C is asked between two 100 ms steps
    path = tmp_path / "plant.toml"
    path.write_text("[plc]\n")
    plant = load_plant(path)
    asked: list[int] = []
    seen: list[str] = []

    def ask() -> bool:
        asked.append(plant.clock.now)
        return len(asked) > 3

    console = Console(plant, interrupted=ask, progress=seen.append)
    assert console.execute("advance 10") == ["interrupted  t = 0.400 s"]
    assert asked == [100_000, 200_000, 300_000, 400_000]
    assert seen == ["advancing to t = 10.000 s (Ctrl-C interrupts)"]
    assert console.execute("time") == ["t = 0.400 s"]  # the plant as it stood


def test_tes_verbs_are_the_module_verbs(tmp_path: Path) -> None:
    # issue 9: input, signal, fault, faults, status and leds the same on a TES and a module;
    # a TES named by endpoint and slave where the slave number alone is ambiguous
    path = tmp_path / "tes.toml"
    path.write_text(
        '[plc]\n[[tes]]\nmodel = "TES 32ET-S"\nslave = 1\nendpoint = "tcp://127.0.0.1:0"\n'
        '[[tes]]\nmodel = "TES 8EA"\nslave = 1\nendpoint = "pty"\n'
    )
    console = Console(load_plant(path))
    with pytest.raises(ConfigError, match="slave number 1 answers on 2 endpoints: name the"):
        console.execute("tes 1 read 0")
    tes = "tes tcp://127.0.0.1:0 1"
    assert console.execute(f"{tes} input 3 on") == [f"{tes} input 3 = on"]
    assert console.execute(f"{tes} fault short_2 on") == [f"{tes} fault short_2 on"]
    assert "short_2: input 2: short circuit (reads 1, §4.1.5)" in console.execute(f"{tes} faults")
    assert console.execute(f"{tes} leds") == ["Pwr=on Run=on Prm=off Wdg=off"]
    assert console.execute("tes pty 1 signal a0 sine offset=5 amplitude=1 period_s=10") == [
        "tes pty 1 signal a0 = sine"
    ]
    assert console.execute("tes pty 1 fault power_off on") == ["tes pty 1 fault power_off on"]
    assert console.execute("tes pty 1 status") == ["TES 1 TES 8EA: off  at pty"]
    status = console.execute("status")
    assert status[-2].startswith("TES 1 TES 32ET-S: on  status H'")
    assert (
        status[-2].endswith("at tcp://127.0.0.1:0") and status[-1] == "TES 1 TES 8EA: off  at pty"
    )
    with pytest.raises(ConfigError, match=r"TES 8EA: no analog input 9 \(allowed: 0, 1"):
        console.execute("tes pty 1 input a9 1.0")
    with pytest.raises(
        ConfigError, match=r"unknown fault 'smoke' for TES 8EA pty 1 \(allowed: no_answer"
    ):
        console.execute("tes pty 1 fault smoke on")
    with pytest.raises(ConfigError, match=r"input 3: 'maybe' not allowed \(allowed 1/0, on/off"):
        console.execute(f"{tes} input 3 maybe")


def test_peek_has_no_side_effect_and_read_has_a_masters(tmp_path: Path) -> None:
    # issue 10 item 19: `tes N read` is a master read (its side effects), `peek` has none
    path = tmp_path / "tes.toml"
    path.write_text('[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "pty"\n')
    console = Console(load_plant(path))
    for line in ("tes 1 input 3 1", "advance 100ms", "tes 1 input 3 0", "advance 100ms"):
        console.execute(line)
    peeked = console.execute("tes 1 peek H'001'")
    assert console.execute("tes 1 peek H'001'") == peeked  # nothing consumed
    assert console.execute("tes 1 read H'001'") == ["tes 1 H'001' = H'0008'"]  # memorized
    assert console.execute("tes 1 read H'001'") == ["tes 1 H'001' = H'0000'"]  # consumed


def test_help_write_and_its_error_agree_on_what_is_writable(console: Console) -> None:
    said = " ".join(console.execute("help write"))
    with pytest.raises(ConfigError) as refused:
        console.execute("write IW5,0 1")
    error = str(refused.value)
    for kind in ("W", "B", "CW", "SY", "SW"):
        assert f" {kind}" in said, said
        assert f"{kind}i" in error, error
    assert "OW" in said and "OW" in error and "Oxy,i" in error
    assert console.execute("write CW3 7") == ["CW3 = 7"]
    assert console.execute("write B4 1") == ["B4 = 1"]
