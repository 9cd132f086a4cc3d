"""Property: any generated plant under any generated stimuli - Modbus requests over a real
TCP connection arriving when the kernel delivers them, console lines, reconnections, time
advanced - recorded with ``plant.record`` and replayed with ``fieldtwin.replay.replay``,
gives the very same outputs."""

from __future__ import annotations

import contextlib
import select
import socket
import struct
import tempfile
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, SimClock
from fieldtwin.console import Console
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant import build_plant, read_plant
from fieldtwin.replay import replay
from fieldtwin.runtime.runner import Runner

DIGITAL = ("TES 32EST", "TES 16EST", "TES 32ST")
ANALOG = ("TES 8EA", "TES 4EA")
REPLY_WAIT_US = 300 * MS  # simulated time a request is given to be answered


def _digital_inputs(draw: Any) -> str:
    period = draw(st.sampled_from([0.1, 0.25, 1.0]))
    seed = draw(st.integers(0, 1000))
    return (
        f'inputs = {{ 0 = {{ kind = "pulse", period_s = {period}, duty = 0.5 }},'
        f' 1 = {{ kind = "random", seed = {seed}, mean_interval_s = 0.3 }},'
        f" 2 = {str(draw(st.booleans())).lower()} }}"
    )


def _analog_inputs(draw: Any) -> str:
    offset = draw(st.floats(1.0, 9.0)).__round__(2)
    seed = draw(st.integers(0, 1000))
    return (
        f'inputs = {{ a0 = {{ kind = "sine", offset = {offset}, amplitude = 1.0, period_s = 2 }},'
        f' a1 = {offset}, a2 = {{ kind = "noise", base = 5.0, sigma = 0.1, seed = {seed},'
        " sample_period_s = 0.05 } }"
    )


@st.composite
def plants(draw: Any) -> str:
    count = draw(st.integers(1, 3))
    parts = ['[plant]\nname = "generated"\n']
    if draw(st.booleans()):
        milliamps = draw(st.floats(4.0, 20.0)).__round__(2)
        parts.append(
            '[[module]]\ntype = "TSX AEM 811"\nrack = 0\nslot = 5\ninputs = [\n'
            f"  {{ channel = 0, milliamps = {milliamps} }},\n"
            '  { channel = 1, milliamps = { kind = "sine", offset = 12.0, amplitude = 4.0,'
            " period_s = 1 } },\n]\n"
        )
    for slave in range(1, count + 1):
        analog = draw(st.booleans())
        model = draw(st.sampled_from(ANALOG if analog else DIGITAL))
        inputs = (
            ""
            if model == "TES 32ST"
            else (_analog_inputs(draw) if analog else _digital_inputs(draw))
        )
        parts.append(
            f'[[tes]]\nmodel = "{model}"\nslave = {slave}\n'
            f'endpoint = "tcp://127.0.0.1:0"\n{inputs}\n'
        )
    return "\n".join(parts)


REQUESTS = st.tuples(
    st.integers(1, 4),  # unit: 4 is nobody
    st.sampled_from([1, 2, 3, 4, 6]),
    st.integers(0, 0x120),
    st.integers(1, 8),
)
CONSOLE = st.sampled_from(
    [
        "tes 1 input 3 true",
        "tes 1 input 0 false",
        "tes 2 input a1 3.5",
        "tes 1 read H'000' 4",
        "tes 1 power cycle",
        "advance 50ms",
        "time",
        "input 5 0 12mA",
    ]
)
ACTIONS = st.lists(
    st.one_of(
        st.tuples(st.just("advance"), st.integers(1, 400)),
        st.tuples(st.just("request"), REQUESTS),
        st.tuples(st.just("console"), CONSOLE),
        st.tuples(st.just("reconnect"), st.none()),
    ),
    min_size=1,
    max_size=25,
)


def _pdu(function: int, address: int, count: int) -> bytes:
    if function == 6:
        return struct.pack(">BHH", 6, address, count)
    return struct.pack(">BHH", function, address, count)


class _Master:
    """A raw Modbus TCP master on a real socket (the twin's runner reads it when it comes)."""

    def __init__(self, port: int) -> None:
        self.port = port
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=2)
        self.sock.setblocking(False)
        self.transaction = 0
        self.received = b""

    def send(self, unit: int, pdu: bytes) -> None:
        self.transaction = (self.transaction + 1) & 0xFFFF
        head = struct.pack(">HHHB", self.transaction, 0, len(pdu) + 1, unit)
        self.sock.setblocking(True)
        self.sock.sendall(head + pdu)
        self.sock.setblocking(False)

    def answered(self) -> bool:
        if select.select([self.sock], [], [], 0)[0]:
            with contextlib.suppress(BlockingIOError):
                self.received += self.sock.recv(4096)
        return len(self.received) >= 6 and len(self.received) >= 6 + self.received[5]

    def take(self) -> None:
        self.received = b""

    def close(self) -> None:
        self.sock.close()


def _session(text: str, actions: list[tuple[str, Any]], directory: Path) -> Path:
    plant_path = directory / "plant.toml"
    plant_path.write_text(text, "utf-8")
    runner = Runner(SimClock(), speed=None)
    plant = build_plant(read_plant(plant_path), runner=runner, speed=None)
    record = directory / "session.ftrec"
    plant.record(record, runner)
    try:
        line = plant.start_endpoints(runner)[0]
        port = int(line.split()[2].rsplit(":", 1)[1])
        console = Console(plant)
        master = _Master(port)
        try:
            for kind, arg in actions:
                if kind == "advance":
                    runner.advance(arg * MS)
                elif kind == "request":
                    unit, function, address, count = arg
                    master.send(unit, _pdu(function, address, count))
                    runner.run_until(master.answered, REPLY_WAIT_US)
                    master.take()
                elif kind == "console":
                    with contextlib.suppress(FieldtwinError):  # a mistake is recorded too
                        console.execute(arg)
                else:
                    master.close()
                    runner.run_until(lambda: False, 20 * MS)  # the close is seen
                    master = _Master(port)
                    runner.run_until(lambda: False, 20 * MS)  # and the new connection
            runner.advance(100 * MS)
        finally:
            master.close()
    finally:
        plant.close()
    return record


@settings(
    max_examples=12,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(plants(), ACTIONS)
def test_a_generated_session_replays_identically(text: str, actions: list[Any]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        record = _session(text, actions, Path(tmp))
        outcome = replay(record)
        assert outcome.identical, f"{text}\n{actions}\n{outcome.difference}"
        assert outcome.inputs >= 1
