"""Generated malformed plant documents get a clear error, never a traceback (issue 10 item 6).

Every document starts from a real plant (the embedded default plant and each example)
and has one key replaced by a value of the wrong type, a huge number or a deep nest,
or gains an unknown key.  Building it either works or raises ConfigError whose
message names the file; nothing else may escape.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fieldtwin.cli import main
from fieldtwin.errors import ConfigError
from fieldtwin.plant import PlantFile, build_plant, read_plant

ROOT = Path(__file__).resolve().parents[2]
SOURCES = [read_plant(None)] + [read_plant(p) for p in sorted((ROOT / "examples").glob("*.toml"))]

JUNK = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([1e308, -1e308, math.inf, -math.inf, math.nan, 0.0, -1, 0, 2**31, 2**63]),
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(["", "²", "\x00", "H'FFFFF'", "max", "TSX 87", "pty?baud=²", "tcp://[::1"]),
    st.lists(st.integers(-5, 5), max_size=4),
    st.dictionaries(st.text(max_size=5), st.integers(-5, 5), max_size=3),
    st.just([[[[[[[[[[1]]]]]]]]]]),
)


def _paths(node: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield path
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, (*path, key))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from _paths(value, (*path, index))


def _replace(data: dict[str, Any], path: tuple[Any, ...], value: Any) -> None:
    node: Any = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value


def _without_real_endpoints(data: dict[str, Any]) -> None:
    """Keep the plants in simulated time: SCM channels on memory peers, TES on port 0."""
    for module in data.get("module", []):
        for channel in module.get("channels", []) if isinstance(module, dict) else []:
            if isinstance(channel, dict) and "endpoint" in channel:
                channel["endpoint"] = "memory"


@st.composite
def documents(draw: st.DrawFn) -> tuple[str, dict[str, Any]]:
    source = draw(st.sampled_from(SOURCES))
    data = copy.deepcopy(dict(source.data))
    _without_real_endpoints(data)
    paths = [p for p in _paths(data) if p]
    if draw(st.booleans()):
        path = draw(st.sampled_from(paths))
        _replace(data, path, draw(JUNK))
    else:
        parent = draw(st.sampled_from([(), *[p for p in paths if isinstance(_at(data, p), dict)]]))
        _at(data, parent)[draw(st.text(min_size=1, max_size=8))] = draw(JUNK)
    return source.name, data


def _at(data: Any, path: tuple[Any, ...]) -> Any:
    for key in path:
        data = data[key]
    return data


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(documents())
def test_a_malformed_plant_is_built_or_refused_with_a_config_error(
    doc: tuple[str, dict[str, Any]],
) -> None:
    name, data = doc
    plant_file = PlantFile("malformed.toml", data, ROOT / "examples")
    try:
        plant = build_plant(plant_file, speed=None)
    except ConfigError as exc:
        assert str(exc).startswith("malformed.toml"), f"{exc} (from {name})"
    else:
        plant.close()


def test_the_generator_reaches_every_source_plant() -> None:
    assert len(SOURCES) >= 4
    for source in SOURCES:
        assert tomllib.loads(Path(ROOT / "examples" / "aem811.toml").read_text())
        assert list(_paths(dict(source.data)))


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return (
            "nan"
            if math.isnan(value)
            else ("inf" if value > 0 else "-inf")
            if math.isinf(value)
            else repr(value)
        )
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return (
        "{" + ", ".join(f"{json.dumps(str(k))} = {_toml_value(v)}" for k, v in value.items()) + "}"
    )


def _toml(data: dict[str, Any]) -> str:
    """The document as TOML: every table inline (enough for generated documents)."""
    return "".join(f"{json.dumps(key)} = {_toml_value(value)}\n" for key, value in data.items())


def _no_real_ports(data: dict[str, Any]) -> None:
    for tes in data.get("tes", []) if isinstance(data.get("tes"), list) else []:
        if isinstance(tes, dict) and isinstance(tes.get("endpoint"), str):
            tes["endpoint"] = "tcp://127.0.0.1:0"


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(doc=documents(), command=st.sampled_from(["run", "console"]))
def test_run_and_console_answer_a_malformed_plant_with_status_2_and_a_message(
    doc: tuple[str, dict[str, Any]], command: str, tmp_path_factory: pytest.TempPathFactory
) -> None:
    _name, data = doc
    _no_real_ports(data)
    folder = tmp_path_factory.mktemp("plant")
    for csv in (ROOT / "examples").glob("*.csv"):
        (folder / csv.name).write_bytes(csv.read_bytes())
    path = folder / "plant.toml"
    path.write_text(_toml(data), encoding="utf-8")
    err = io.StringIO()
    args = (
        ["--no-live", "--duration", "0.05", "--speed", "max"]
        if command == "run"
        else ["-c", "time"]
    )
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = main([command, str(path), *args])  # an escaping exception fails the test
    assert status in (0, 2), (status, err.getvalue())
    if status == 2:
        assert f"{path}" in err.getvalue() or "plant.toml" in err.getvalue(), err.getvalue()
