"""A recording is untrusted input (issue 20, R7): whatever a file holds, `fieldtwin replay`
exits 0, 1 or 2 with a message naming the file and line, in bounded memory and time, never
with a traceback, and reads or writes no file outside its own temporary folder."""

from __future__ import annotations

import gzip
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fieldtwin.cli import main
from fieldtwin.errors import ConfigError
from fieldtwin.replay import replay
from fieldtwin.runtime.recfile import MAX_SIM_US, RecordingError
from fieldtwin.runtime.record import read_recording
from tests.record.runs import ROOT
from tests.record.test_property import _session

PLANT = """[plant]
name = "untrusted"

[[module]]
type = "TSX AEM 811"
rack = 0
slot = 5
inputs = [
  { channel = 0, milliamps = { kind = "sine", offset = 12.0, amplitude = 4.0, period_s = 1 } },
]

[[tes]]
model = "TES 8EA"
slave = 1
endpoint = "tcp://127.0.0.1:0"
store = "eeprom.db"
inputs = { a0 = { kind = "sine", offset = 5.0, amplitude = 1.0, period_s = 2 }, a1 = 2.5 }
"""
ACTIONS: list[tuple[str, Any]] = [
    ("request", (1, 4, 0, 2)),
    ("console", "tes 1 input a1 3.5"),
    ("advance", 150),
    ("request", (1, 3, 0x100, 2)),
    ("reconnect", None),
    ("request", (2, 4, 0, 1)),
    ("console", "advance 50ms"),
    ("advance", 100),
]
MAX_RSS_KB = 200 * 1024  # a replay of anything stays within 200 MB


@pytest.fixture(scope="module")
def seed(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    """The lines of a real recording: connections, Modbus bytes, console lines, a store."""
    directory = tmp_path_factory.mktemp("seed")
    record = _session(PLANT, ACTIONS, directory)
    header, records = read_recording(record)
    kinds = {r[0] for r in records}
    assert {"bind", "accept", "data", "send", "line", "ret", "result", "object"} <= kinds
    assert "eeprom.db" in header.files
    with gzip.open(record, "rt", encoding="utf-8") as file:
        return file.read().splitlines()


def _write(path: Path, lines: list[str]) -> Path:
    with gzip.open(path, "wt", encoding="utf-8") as file:
        file.write("\n".join(lines) + "\n")
    return path


def _fieldtwin(*argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=120,
    )


def test_the_seed_replays_identically(seed: list[str], tmp_path: Path) -> None:
    outcome = replay(_write(tmp_path / "seed.ftrec", seed))
    assert outcome.identical, outcome.difference


def _at(seed: list[str], kind: str) -> int:
    return next(i for i, line in enumerate(seed) if i > 0 and json.loads(line)[0] == kind)


# a damaged record of each kind of damage: (what, the lines, the message expected)
def _damaged(seed: list[str]) -> list[tuple[str, list[str], str]]:
    head, body = seed[0], seed[1:]
    data = _at(seed, "data")
    end = json.loads(seed[-1])
    assert end[0] == "end"
    return [
        ("fields of the wrong kind", [head, '["data",{},[],null,5]', *body], "line 2: time {}"),
        (
            "a short line record",
            [head, '["line", 0, 0]', *body],
            "line 2: a 'line' record has 4 fields",
        ),
        ("nested 200,000 deep", [head, "[" * 200_000 + "]" * 200_000, *body], "nested more"),
        (
            "a time of 1e30",
            [*seed[:-1], f'["ret", {10**30}, {end[2]}]', seed[-1]],
            f"line {len(seed)}: time {10**30} is not a whole number of microseconds",
        ),
        ("a float time", [head, '["ret", 1e30, 0]', *body], "line 2: time 1e+30"),
        ("a record after the end", [*seed, seed[-1]], "record after the end record"),
        (
            "bytes that are not hex",
            [*seed[:data], '["data", 0, 0, "t1", "zz"]', *seed[data:]],
            'bytes "zz" is not hexadecimal bytes',
        ),
        ("not JSON", [head, '["data", 0,', *body], "line 2: not JSON"),
        ("a 5000-digit number", [head, f'["ret", {"9" * 5000}, 0]', *body], "line 2: not JSON"),
        ("an unknown record", [head, '["teleport", 0]', *body], "unknown record 'teleport'"),
        (
            "a control command that is not one",
            [head, '["call", 0, 0, "__init__", []]', *body],
            "line 2: '__init__' is not a recorded control command",
        ),
        (
            "a control command with too many arguments",
            [head, '["call", 0, 0, "set_input", [1, 2, 3, 4, 5, 6, 7]]', *body],
            "line 2: control set_input: too many positional arguments",
        ),
        (
            "a control command with an argument of the wrong kind",
            [head, '["call", 0, 0, "set_speed", ["fast"]]', *body],
            "line 2: control set_speed: refused (TypeError",
        ),
        (
            "an unknown port group",
            [head, '["bind", 0, 0, ["modbus", "nope"]]', *body],
            "line 2: bind: unknown port group(s) ['nope']",
        ),
        ("not a record", [head, '{"a": 1}', *body], "line 2: not a record"),
    ]


def test_every_damage_is_named_with_its_line_never_a_traceback(
    seed: list[str], tmp_path: Path
) -> None:
    for index, (what, lines, message) in enumerate(_damaged(seed)):
        path = _write(tmp_path / f"damaged-{index}.ftrec", lines)
        with pytest.raises(RecordingError) as caught:
            replay(path)
        assert str(caught.value).startswith(f"{path}: line "), what
        assert message in str(caught.value), (what, str(caught.value))
    # the same through the command: exit 2, the message, no traceback
    path = _write(tmp_path / "cli.ftrec", _damaged(seed)[2][1])
    result = _fieldtwin("replay", str(path), cwd=tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr == f"fieldtwin: {path}: line 2: nested more than 64 deep\n"


def test_an_endless_line_is_refused_at_the_bound_unread(seed: list[str], tmp_path: Path) -> None:
    """1 GiB without a newline: refused once 1 MiB of it is read (a gzip of many members
    of the same 16 MiB of 'a': the rest is never inflated)."""
    chunk = gzip.compress(b"a" * (16 << 20), compresslevel=9)
    path = tmp_path / "endless.ftrec"
    with path.open("wb") as file:
        file.write(gzip.compress(seed[0].encode("utf-8") + b"\n"))
        file.write(gzip.compress(b'["line", 0, 0, "'))
        for _ in range(64):
            file.write(chunk)
    code = (
        "import resource, subprocess, sys\n"
        f"r = subprocess.run([sys.executable, '-m', 'fieldtwin', 'replay', {str(path)!r}],"
        " capture_output=True, text=True, timeout=120)\n"
        "print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
        "print(r.stderr, end='')\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=180
    )
    first, _, stderr = result.stdout.partition("\n")
    status, rss = (int(v) for v in first.split())
    assert status == 2, result.stdout + result.stderr
    assert stderr == f"fieldtwin: {path}: line 2: longer than 1 MiB (a record is at most 1 MiB)\n"
    assert rss <= MAX_RSS_KB, f"{rss} kB"


def _bomb(path: Path, header: str, members: int) -> int:
    """A gzip of many members, each 32 MiB of valid ``ret`` records at t = 0 (padded with
    JSON's blanks: deflate's best ratio, about 1000): some 3 MB of file, 3 GiB of text.
    The inflated size."""
    line = b'["ret",0,0]' + b" " * (256 * 1024 - 12) + b"\n"
    block = line * ((32 << 20) // len(line))
    member = gzip.compress(block, compresslevel=9)
    with path.open("wb") as file:
        file.write(gzip.compress(header.encode("utf-8") + b"\n"))
        for _ in range(members):
            file.write(member)
    return len(block) * members


def test_a_gzip_bomb_is_refused_within_200_mb(seed: list[str], tmp_path: Path) -> None:
    path = tmp_path / "bomb.ftrec"
    inflated = _bomb(path, seed[0], 96)
    size = path.stat().st_size
    assert size < 3_500_000 and inflated >= 3 << 30, (size, inflated)
    code = (
        "import resource, subprocess, sys\n"
        f"r = subprocess.run([sys.executable, '-m', 'fieldtwin', 'replay', {str(path)!r}],"
        " capture_output=True, text=True, timeout=150)\n"
        "print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
        "print(r.stderr, end='')\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=200
    )
    first, _, stderr = result.stdout.partition("\n")
    status, rss = (int(v) for v in first.split())
    assert status == 2, result.stdout + result.stderr
    assert stderr.startswith(f"fieldtwin: {path}: line ") and "gzip bomb" in stderr, stderr
    assert rss <= MAX_RSS_KB, f"{rss} kB"


def test_the_embedded_plant_names_no_file_outside_the_replay(
    seed: list[str], tmp_path: Path
) -> None:
    planted = tmp_path / "planted.db"
    cases = {
        "store": ('store = "eeprom.db"', f'store = "{planted}"'),
        "climbing store": ('store = "eeprom.db"', 'store = "../../planted.db"'),
        "program": ("[[tes]]", '[plc]\nprogram = "/etc/passwd"\n\n[[tes]]'),
        "csv": ("a1 = 2.5", 'a1 = { kind = "csv", file = "/etc/passwd" }'),
    }
    for what, (old, new) in cases.items():
        header = json.loads(seed[0])
        assert old in header["plant"]["text"]
        header["plant"]["text"] = header["plant"]["text"].replace(old, new)
        path = _write(tmp_path / f"{what}.ftrec", [json.dumps(header), *seed[1:]])
        result = _fieldtwin("replay", str(path), cwd=tmp_path)
        assert result.returncode == 2, (what, result.stdout + result.stderr)
        assert "is a path outside the replay's folder" in result.stderr, result.stderr
        assert "root:" not in result.stdout + result.stderr  # nothing of the file
        assert "Traceback" not in result.stderr
    assert not planted.exists() and not (tmp_path.parent / "planted.db").exists()


def test_a_file_the_recording_embeds_is_read_from_the_recording(
    seed: list[str], tmp_path: Path
) -> None:
    """An absolute name the recording embeds is the recording's copy, in the replay's
    folder: the store named /nonexistent/... is never created."""
    header = json.loads(seed[0])
    target = "/nonexistent/fieldtwin/eeprom.db"
    header["plant"]["text"] = header["plant"]["text"].replace('"eeprom.db"', f'"{target}"')
    header["plant"]["files"] = {target: header["plant"]["files"]["eeprom.db"]}
    outcome = replay(_write(tmp_path / "embedded.ftrec", [json.dumps(header), *seed[1:]]))
    assert outcome.identical, outcome.difference
    assert not Path(target).exists()


def test_a_command_past_the_recordings_end_stops_there(seed: list[str], tmp_path: Path) -> None:
    """`advance 1000000000` in a recording that ends at 0.4 s: the replay stops at the
    end (a difference, said), it does not run 30 years of simulated time."""
    lines = [seed[0], '["line", 0, 0, "advance 1000000000"]', *seed[1:]]
    outcome = replay(_write(tmp_path / "long.ftrec", lines))
    assert not outcome.identical and outcome.difference is not None
    assert "the replay stopped at the recording's end" in outcome.difference
    assert "the command of line 2 asked to run to" in outcome.difference
    assert outcome.sim_us == json.loads(seed[-1])[1]


def test_header_fields_are_checked_and_unknown_ones_refused(
    seed: list[str], tmp_path: Path
) -> None:
    good = json.loads(seed[0])
    cases: list[tuple[dict[str, Any], str]] = [
        ({**good, "consoles": "inline"}, "unknown header field(s) 'consoles'"),
        ({**good, "console": "batch"}, "console must be 'inline' or 'modes'"),
        ({**good, "sample_ms": 0}, "sample_ms must be a whole number of ms from 10"),
        ({**good, "speed": -1}, "speed must be null"),
        ({**good, "speed": True}, "speed must be null"),
        ({**good, "plant": {**good["plant"], "extra": 1}}, "plant must be an object with"),
        (
            {**good, "plant": {**good["plant"], "files": {"a\0b": "x"}}},
            "must be a file name (no NUL)",
        ),
        (
            {**good, "plant": {**good["plant"], "files": {"x": "\u20ac"}}},
            "a file's bytes (latin-1 text)",
        ),
        ({**good, "plant": {**good["plant"], "text": 5}}, "plant.text must be"),
    ]
    for index, (header, message) in enumerate(cases):
        path = _write(tmp_path / f"header-{index}.ftrec", [json.dumps(header), *seed[1:]])
        with pytest.raises(ConfigError) as caught:
            replay(path)
        assert str(caught.value).startswith(f"{path}: line 1: "), str(caught.value)
        assert message in str(caught.value), (message, str(caught.value))


def test_a_fifo_is_not_opened(tmp_path: Path) -> None:
    import os

    fifo = tmp_path / "fifo.ftrec"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="not a regular file"):
        replay(fifo)


def test_the_time_bound_is_seven_days() -> None:
    assert MAX_SIM_US == 7 * 24 * 3600 * 10**6


# ------------------------------------------------------------------------- the fuzz

SCALARS = (
    st.none()
    | st.booleans()
    | st.integers(-1, 2_000_000)
    | st.sampled_from([10**30, 2**63, MAX_SIM_US + 1, -(2**40)])
    | st.floats(allow_nan=False, allow_infinity=False, width=32)
    | st.text(max_size=6)
    | st.sampled_from(["t1", "l1", "ret", "data", "call", "line", "end", "0102", "advance 1"])
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner, max_size=2)
    ),
    max_leaves=6,
)
MUTATIONS = st.lists(
    st.tuples(
        st.sampled_from(["drop", "dup", "swap", "field", "cut", "insert", "header"]),
        st.integers(0, 10**6),
        st.integers(0, 10**6),
        VALUES,
    ),
    min_size=1,
    max_size=4,
)


def _mutate(seed: list[str], mutations: list[tuple[str, int, int, Any]]) -> list[str]:
    lines = list(seed)
    for kind, i, j, value in mutations:
        n = len(lines)
        at = 1 + i % max(1, n - 1) if n > 1 else 0
        if kind == "drop" and n > 1:
            del lines[at]
        elif kind == "dup" and n > 1:
            lines.insert(at, lines[at])
        elif kind == "swap" and n > 2:
            other = 1 + j % (n - 1)
            lines[at], lines[other] = lines[other], lines[at]
        elif kind == "field" and n > 1:
            try:
                record = json.loads(lines[at])
            except ValueError:
                continue
            if isinstance(record, list) and record:
                record[j % len(record)] = value
                lines[at] = json.dumps(record)
        elif kind == "cut" and n > 1:
            lines[at] = lines[at][: j % max(1, len(lines[at]))]
        elif kind == "insert":
            lines.insert(
                at, json.dumps(value if isinstance(value, list) else [value, j % 500_000, 0])
            )
        elif kind == "header":
            header = json.loads(lines[0]) if lines else {}
            keys = sorted(header) or ["format"]
            header[keys[j % len(keys)]] = value
            lines[0] = json.dumps(header)
    return lines


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(MUTATIONS)
def test_any_mutated_recording_replays_or_is_refused_with_a_message(
    seed: list[str],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    mutations: list[tuple[str, int, int, Any]],
) -> None:
    path = _write(tmp_path / "mutated.ftrec", _mutate(seed, mutations))
    capsys.readouterr()
    status = main(["replay", str(path)])  # any exception here is a traceback: a failure
    out, err = capsys.readouterr()
    assert status in (0, 1, 2), (status, out, err)
    if status == 0:
        assert out.startswith("identical: ")
    elif status == 1:
        assert out.startswith("different: ") and "first difference" in out
    else:
        assert err.startswith(f"fieldtwin: {path}: "), err
        assert "Traceback" not in err


def test_a_damaged_deflate_stream_is_named(tmp_path: Path, seed: list[str]) -> None:
    """Bytes that are no deflate stream after a valid header: a message, exit 2."""
    path = tmp_path / "garbage.ftrec"
    path.write_bytes(gzip.compress((seed[0] + "\n").encode()) + b"\x1f\x8b\x08\x00" + bytes(64))
    result = _fieldtwin("replay", str(path), cwd=tmp_path)
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.startswith(f"fieldtwin: {path}: ")


def test_an_input_stamped_before_an_output_of_its_instant_is_accepted() -> None:
    """Bytes that arrived at 1099324 us, taken at the instant 1100000 us after its outputs
    were written (a loaded machine's paced run): the inputs' order is their clock events."""
    from fieldtwin.runtime.recfile import Checker, RecordingError

    checker = Checker("x.ftrec")
    checker.check(["object", 1_100_000, "5", "IW5,0", 1], 2)
    checker.check(["data", 1_099_324, 10, "t1", "00"], 3)
    with pytest.raises(RecordingError, match="clock events never run backwards"):
        checker.check(["data", 1_099_400, 9, "t1", "00"], 4)
    checker.check(["chars", 1_000_000, "5", 0, "in", "41"], 5)  # a block begun earlier
