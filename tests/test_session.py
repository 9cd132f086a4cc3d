"""The Session: steps undone in reverse, every one, on errors too (fieldtwin.session)."""

from __future__ import annotations

import socket
import threading
from pathlib import Path

import pytest

from fieldtwin.errors import FieldtwinError
from fieldtwin.plant import build_plant, read_plant
from fieldtwin.session import ControlOptions, RunOptions, Session, open_run


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_close_undoes_every_step_last_first_even_when_one_fails() -> None:
    session = Session(build_plant(read_plant(None)))
    done: list[str] = []

    def fail() -> None:
        done.append("b")
        raise OSError("b failed")

    session.push(lambda: done.append("a"))
    session.push(fail)
    session.push(lambda: done.append("c"))
    with pytest.raises(OSError, match="b failed"):
        session.close()
    assert done == ["c", "b", "a"]
    session.close()  # nothing left to undo
    assert done == ["c", "b", "a"]


def test_a_port_that_cannot_open_closes_what_the_run_had_opened(
    tmp_path: Path, signal_handlers: None
) -> None:
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    port = busy.getsockname()[1]
    plant = tmp_path / "plant.toml"
    plant.write_text(
        f'[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:{port}"\n'
    )
    control_port = _free_port()
    threads = set(threading.enumerate())
    options = RunOptions(
        plant=str(plant),
        live=False,
        trace=str(tmp_path / "trace.jsonl"),
        control=ControlOptions(port=control_port),
    )
    try:
        with pytest.raises(FieldtwinError, match=str(port)):
            open_run(options)
    finally:
        busy.close()
    # the control API was up (it starts before the ports): its port is free again,
    # the observers' thread and the server's threads are gone, the trace is closed
    with socket.socket() as again:
        again.bind(("127.0.0.1", control_port))
    left = [t for t in set(threading.enumerate()) - threads if t.is_alive()]
    assert left == []
    assert (tmp_path / "trace.jsonl").exists()


def test_a_run_binds_every_port_after_its_windows(tmp_path: Path, signal_handlers: None) -> None:
    port = _free_port()
    plant = tmp_path / "plant.toml"
    plant.write_text(
        f'[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:{port}"\n'
    )
    session = open_run(RunOptions(plant=str(plant), live=False, control=None))
    try:
        assert session.control is None
        assert len(session.lines) == 1 and f"tcp://127.0.0.1:{port}" in session.lines[0]
        with socket.create_connection(("127.0.0.1", port), timeout=5):
            pass  # listening
    finally:
        session.close()
    with socket.socket() as again:  # closed with the session
        again.bind(("127.0.0.1", port))
