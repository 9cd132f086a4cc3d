"""Plant-file tables and CSV files -> signals (fieldtwin.signals.spec, .table)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.errors import ConfigError
from fieldtwin.signals import (
    KINDS,
    Constant,
    DiscreteConstant,
    Edges,
    Noise,
    PiecewiseLinear,
    PulseTrain,
    Ramp,
    RandomEdges,
    Sine,
    Square,
    Step,
    Sum,
    analog_from_spec,
    discrete_from_spec,
    is_discrete,
    signal_from_spec,
)

WHERE = "plant.toml: module[0].inputs[3].signal"


def build(spec: dict[str, object], base_dir: Path | None = None) -> object:
    return signal_from_spec(spec, where=WHERE, base_dir=base_dir)


# --- every kind ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ({"kind": "constant", "value": 3.2}, Constant(3.2)),
        ({"kind": "constant", "value": 4}, Constant(4.0)),
        ({"kind": "constant", "value": True}, DiscreteConstant(True)),
        ({"kind": "step", "before": 4, "after": 20, "at_s": 1.5}, Step(4.0, 20.0, 1_500_000)),
        (
            {"kind": "ramp", "start": 4, "end": 20, "t0_s": 0, "duration_s": 30},
            Ramp(4.0, 20.0, 0, 30 * S),
        ),
        ({"kind": "ramp", "start": 4, "end": 20, "duration_s": 0.5}, Ramp(4.0, 20.0, 0, 500 * MS)),
        (
            {"kind": "sine", "offset": 5.0, "amplitude": 2.0, "period_s": 60},
            Sine(5.0, 2.0, 60 * S),
        ),
        (
            {"kind": "sine", "amplitude": 1, "period_s": 0.02, "phase_deg": 90},
            Sine(0.0, 1.0, 20 * MS, 90.0),
        ),
        (
            {"kind": "square", "low": 0, "high": 10, "period_s": 2, "duty": 0.25},
            Square(0.0, 10.0, 2 * S, 0.25),
        ),
        (
            {"kind": "pwl", "points": [[0, 4.0], [10.5, 20.0]]},
            PiecewiseLinear([(0, 4.0), (10_500_000, 20.0)]),
        ),
        (
            {"kind": "noise", "base": {"kind": "constant", "value": 5}, "sigma": 0.01, "seed": 1},
            Noise(Constant(5.0), 0.01, 1, 1 * MS),
        ),
        (
            {"kind": "noise", "sigma": 0.5, "seed": 2, "sample_period_s": 0.1},
            Noise(Constant(0.0), 0.5, 2, 100 * MS),
        ),
        (
            {"kind": "sum", "terms": [2.5, {"kind": "step", "before": 0, "after": 1, "at_s": 1}]},
            Sum([Constant(2.5), Step(0.0, 1.0, 1 * S)]),
        ),
        ({"kind": "pulse", "period_s": 30, "duty": 0.01}, PulseTrain(30 * S, 0.01)),
        (
            {"kind": "pulse", "period_s": 1, "start_s": 2, "high_first": False},
            PulseTrain(1 * S, 0.5, 2 * S, False),
        ),
        (
            {"kind": "edges", "initial": False, "times_s": [1.0, 1.5]},
            Edges(False, [1 * S, 1_500_000]),
        ),
        (
            {"kind": "edges", "changes": [[0.5, True], [0.7, True], [2, False]]},
            Edges(False, [500 * MS, 2 * S]),
        ),
        ({"kind": "random", "seed": 3, "mean_interval_s": 2.0}, RandomEdges(3, 2 * S, 1 * MS)),
        (
            {
                "kind": "random",
                "seed": 3,
                "mean_interval_s": 2,
                "min_interval_s": 0.5,
                "initial": True,
            },
            RandomEdges(3, 2 * S, 500 * MS, True),
        ),
    ],
)
def test_every_kind(spec: dict[str, object], expected: object) -> None:
    assert build(spec) == expected


def test_every_kind_is_tested_and_documented() -> None:
    docs = (Path(__file__).parents[2] / "docs" / "signals.md").read_text()
    for kind in KINDS:
        assert f'kind = "{kind}"' in docs, kind


def test_csv_relative_to_base_dir(tmp_path: Path) -> None:
    (tmp_path / "level.csv").write_text("time_s,level\n0,4.0\n10,20.0\n")
    signal = build({"kind": "csv", "file": "level.csv"}, base_dir=tmp_path)
    assert signal == PiecewiseLinear([(0, 4.0), (10 * S, 20.0)])


def test_analog_and_discrete_helpers() -> None:
    assert analog_from_spec(2.5, where=WHERE) == Constant(2.5)
    assert discrete_from_spec(False, where=WHERE) == DiscreteConstant(False)
    assert is_discrete(discrete_from_spec({"kind": "pulse", "period_s": 1}, where=WHERE))
    with pytest.raises(ConfigError, match=r"^plant.toml: .*: a discrete signal where an analog"):
        analog_from_spec(True, where=WHERE)
    with pytest.raises(ConfigError, match="an analog signal where a discrete one is needed"):
        discrete_from_spec(3.0, where=WHERE)
    with pytest.raises(ConfigError, match="is not a table"):
        discrete_from_spec("on", where=WHERE)


# --- every mistake names where and what is allowed -------------------------------------


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"kind": "sinus"}, ".kind: unknown signal kind 'sinus' (allowed constant, step, ramp"),
        ({"value": 1}, ".kind: missing (allowed constant"),
        ({"kind": 3}, ".kind: unknown signal kind 3"),
        ({"kind": ["sine"]}, ".kind: unknown signal kind ['sine']"),
        ({"kind": "edges", "times_s": [float("nan")]}, ".times_s[0]: nan is not a number"),
        ({"kind": "constant"}, ".value: missing"),
        ({"kind": "constant", "value": "3"}, ".value: '3' is not a number"),
        ({"kind": "sine", "amplitude": 1, "period": 60}, ".period: unknown field for this kind"),
        ({"kind": "sine", "amplitude": 1, "period_s": 0}, ".period_s: 0.0 s is not a duration"),
        ({"kind": "sine", "amplitude": 1, "period_s": -1}, ".period_s: -1.0 s is not a duration"),
        ({"kind": "step", "before": 0, "after": 1, "at_s": -1}, ".at_s: -1.0 s is negative"),
        (
            {"kind": "pulse", "period_s": 30, "duty": 2},
            ".duty: 2.0 is not a fraction (allowed 0..1)",
        ),
        ({"kind": "pulse", "period_s": 30, "high_first": 1}, ".high_first: 1 is not true or false"),
        ({"kind": "edges", "times_s": [1.0, 0.5]}, ": edge 1: time 500000 us is not after"),
        ({"kind": "edges", "times_s": 1.0}, ".times_s: 1.0 is not a list"),
        ({"kind": "edges", "times_s": ["a"]}, ".times_s[0]: 'a' is not a number of seconds"),
        ({"kind": "edges", "times_s": [1], "changes": []}, "either times_s or changes"),
        ({"kind": "edges", "changes": [[1, 1]]}, ".changes[0]: value 1 is not true or false"),
        ({"kind": "edges", "changes": [1]}, ".changes[0]: 1 is not a pair"),
        ({"kind": "pwl", "points": [[0, "x"]]}, ".points[0]: value 'x' is not a number"),
        ({"kind": "pwl", "points": [[-1, 2]]}, ".points[0]: time -1 is not a number"),
        ({"kind": "pwl", "points": []}, "at least one"),
        ({"kind": "random", "seed": 1.5, "mean_interval_s": 1}, ".seed: 1.5 is not a whole"),
        ({"kind": "random", "seed": 1, "mean_interval_s": 0.0001}, "allowed mean >= min"),
        ({"kind": "noise", "sigma": 1, "seed": 1, "base": True}, ".base: a discrete signal"),
        ({"kind": "noise", "sigma": 1, "seed": 1, "base": {"kind": "x"}}, ".base.kind: unknown"),
        ({"kind": "sum", "terms": [1, {"kind": "pulse", "period_s": 1}]}, ".terms[1]: a discrete"),
        ({"kind": "csv"}, ".file: missing"),
        ({"kind": "csv", "file": ""}, ".file: '' is not a file name"),
        ({"kind": "csv", "file": "/nonexistent/level.csv"}, "cannot read the signal file"),
    ],
)
def test_mistakes(spec: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError) as info:
        build(spec)
    text = str(info.value)
    assert text.startswith(WHERE), text
    assert message in text, text


def test_not_a_table() -> None:
    with pytest.raises(ConfigError, match=r"^here: 3 is not a table"):
        signal_from_spec(3, where="here")  # type: ignore[arg-type]


# --- CSV files -------------------------------------------------------------------------


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "signal.csv"
    path.write_text(text)
    return path


def test_csv_without_header_with_comments_and_blanks(tmp_path: Path) -> None:
    path = write(tmp_path, "# level of tank 1\n0, 4\n\n0.5,8.5\n0.5,2\n  2 ,2\n")
    signal = PiecewiseLinear.from_csv(path)
    assert signal.points == ((0, 4.0), (500 * MS, 8.5), (500 * MS, 2.0), (2 * S, 2.0))
    assert signal.value_at(250 * MS) == pytest.approx(6.25)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,value\n0,1\nx,2\n", ":3: column 1 (time_s) is not a finite number"),
        ("0,1\ntime,value\n", ":2: column 1 (time_s) is not a finite number"),
        ("0,1\n2,3,4\n", ":2: 3 columns, not 2"),
        ("0,1\n1\n", ":2: 1 column, not 2"),
        ("0,1\n2,1\n1,1\n", ":3: the time is before the previous row's"),
        ("-1,1\n", ":1: the time is negative"),
        ("0,nan\n", ":1: column 2 (value) is not a finite number"),
        ("time,value\n", ": no data rows"),
        ("", ": no data rows"),
        ("0,1\n0,2\n0,3\n", "three points at 0 us"),
    ],
)
def test_csv_mistakes_name_file_line_and_form(tmp_path: Path, text: str, message: str) -> None:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        PiecewiseLinear.from_csv(path)
    shown = str(info.value)
    assert shown.startswith(str(path)), shown
    assert message in shown, shown
    if "three points" not in message:
        assert "allowed: 'time_s,value' with two numbers" in shown


def test_csv_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "signal.csv"
    path.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(ConfigError, match="not a UTF-8 text file"):
        PiecewiseLinear.from_csv(path)


def test_csv_error_through_spec_names_where_and_file(tmp_path: Path) -> None:
    write(tmp_path, "0,1\nbad,row\n")
    with pytest.raises(ConfigError) as info:
        build({"kind": "csv", "file": "signal.csv"}, base_dir=tmp_path)
    assert str(info.value).startswith(f"{WHERE}: {tmp_path / 'signal.csv'}:2:")


# --- any table: a signal or a ConfigError, never another exception -------------------

_FIELDS = sorted({name for _, allowed in KINDS.values() for name in allowed} | {"bogus"})
_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10, 10**6) | st.floats() | st.text(max_size=3),
    lambda inner: st.lists(inner, max_size=3),
    max_leaves=6,
)


@settings(max_examples=300, deadline=None)
@given(
    st.sampled_from([*KINDS, "nope"]),
    st.dictionaries(st.sampled_from(_FIELDS), _values, max_size=5),
)
def test_any_table_builds_or_says_why(kind: str, fields: dict[str, object]) -> None:
    spec = {"kind": kind, **fields}
    spec.pop("file", None)  # no file system access from generated tables
    try:
        signal = signal_from_spec(spec, where=WHERE)
    except ConfigError as exc:
        assert str(exc).startswith(WHERE)
    else:
        value = signal.value_at(1_000_000)
        assert isinstance(value, bool) or math.isfinite(value)


def test_csv_from_an_endless_device_is_refused_with_a_bound() -> None:
    # issue 10 item 6: /dev/zero was read without a bound
    refused = r"/dev/zero: a character device, not a regular file \(allowed: .* 16 MiB"
    with pytest.raises(ConfigError, match=refused):
        build({"kind": "csv", "file": "/dev/zero"}, base_dir=Path("/"))
