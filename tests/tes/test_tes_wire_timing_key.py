"""Issue 15 item 2: the plant key ``wire_timing`` switches the RTU wire timing per endpoint."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import build_tes, serve_group
from fieldtwin.modbus.line import RtuLine
from fieldtwin.modbus.model import Link
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.url import parse_endpoint


def _build(tmp_path: Path, *tables: dict[str, Any]) -> list[Any]:
    return build_tes(list(tables), SimClock(), "plant.toml", tmp_path)


def test_wire_timing_is_true_or_false(tmp_path: Path) -> None:
    table = {"model": "TES 8EA", "slave": 4, "endpoint": "pty", "wire_timing": "off"}
    with pytest.raises(
        ConfigError,
        match=r"^plant\.toml: tes\[0\]\.wire_timing: 'off' not allowed \(allowed: true, false\)$",
    ):
        _build(tmp_path, table)


def test_one_line_has_one_wire_timing(tmp_path: Path) -> None:
    a = {"model": "TES 8EA", "slave": 4, "endpoint": "pty"}
    b = {"model": "TES 32ST", "slave": 5, "endpoint": "pty", "wire_timing": False}
    with pytest.raises(
        ConfigError,
        match=r"^plant\.toml: tes\[1\]\.wire_timing: false on pty, where tes\[0\] has true",
    ):
        _build(tmp_path, a, b)
    a["wire_timing"] = False
    assert [tes.wire_timing for tes in _build(tmp_path, a, b)] == [False, False]


@pytest.mark.parametrize("wire", [True, False])
def test_serve_group_follows_the_key(tmp_path: Path, wire: bool) -> None:
    (tes,) = _build(tmp_path, {"model": "TES 8EA", "endpoint": "pty", "wire_timing": wire})
    runner = Runner(tes.clock, speed=None)
    server = serve_group(runner, parse_endpoint("pty"), [tes], Link.RS485)
    try:
        (pump,) = server.pumps.values()
        assert isinstance(pump.core, RtuLine)
        assert (pump.core.wire is not None) is wire
    finally:
        server.close()
