"""One command door: commands are values run by one dispatcher, which observers watch."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from fieldtwin.control.sim import COMMANDS, serve
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.door import CALL, LINE, Command, Door
from fieldtwin.runtime.inbox import Inbox

SRC = Path(__file__).resolve().parents[2] / "src" / "fieldtwin"


class Log:
    """An observer that writes what it sees."""

    def __init__(self) -> None:
        self.seen: list[tuple[object, ...]] = []

    def before(self, command: Command) -> None:
        self.seen.append(("before", command.kind, command.name, command.args))

    def after(self, command: Command, answer: object, error: BaseException | None) -> None:
        self.seen.append(("after", command.name, answer, None if error is None else str(error)))


def test_a_command_is_run_by_its_kinds_handler_between_before_and_after() -> None:
    door, log = Door(), Log()
    door.serve(CALL, lambda c: f"{c.name}{c.args}")
    door.watch(log)
    assert door.dispatch(Command.call("set_speed", 2.0)) == "set_speed(2.0,)"
    assert log.seen == [
        ("before", CALL, "set_speed", (2.0,)),
        ("after", "set_speed", "set_speed(2.0,)", None),
    ]
    assert door.executed == 1


def test_a_command_run_inside_another_is_the_outer_ones_own() -> None:
    door, log = Door(), Log()
    door.serve(CALL, lambda c: c.name)
    door.watch(log)

    def outer(command: Command) -> object:
        assert door.running
        return [door.dispatch(Command.call("set_input", 1)), "done"]

    assert door.dispatch(Command.line("input 5 0 1"), outer) == ["set_input", "done"]
    assert [entry[:3] for entry in log.seen] == [
        ("before", LINE, "input 5 0 1"),
        ("after", "input 5 0 1", ["set_input", "done"]),
    ]
    assert not door.running


def test_an_error_is_seen_after_and_still_raised_and_the_door_runs_on() -> None:
    door, log = Door(), Log()

    def refuse(command: Command) -> object:
        raise ConfigError(f"{command.name}: no")

    door.serve(CALL, refuse)
    door.watch(log)
    with pytest.raises(ConfigError, match="pause: no"):
        door.dispatch(Command.call("pause"))
    assert log.seen[-1] == ("after", "pause", None, "pause: no")
    assert not door.running
    assert door.dispatch(Command.line("time"), lambda c: ["t = 0"]) == ["t = 0"]


def test_an_observer_stopped_sees_no_more_and_a_handler_withdrawn_gives_way() -> None:
    door, log = Door(), Log()
    first = door.serve(CALL, lambda c: "first")
    second = door.serve(CALL, lambda c: "second")
    stop = door.watch(log)
    assert door.dispatch(Command.call("pause")) == "second"
    stop()
    second()
    assert door.dispatch(Command.call("pause")) == "first"
    assert len(log.seen) == 2
    first()
    with pytest.raises(ConfigError, match="no call handler"):
        door.dispatch(Command.call("pause"))
    with pytest.raises(ValueError, match="unknown command kind"):
        door.serve("poke", lambda c: None)


def test_the_inbox_hands_command_values_to_the_door_in_order_with_functions() -> None:
    door, log = Door(), Log()
    door.serve(CALL, lambda c: c.args[0])
    door.watch(log)
    inbox = Inbox(door=door)
    reads: list[int] = []
    first = inbox.submit_command(Command.call("set_input", 1), then=lambda a: (a, "then"))
    read = inbox.submit(lambda: reads.append(len(log.seen)) or "read")
    second = inbox.submit_command(Command.call("set_input", 2))
    assert log.seen == []  # nothing runs before the simulation's turn
    assert inbox.run_pending() == 3
    assert first.result(0) == (1, "then")
    assert read.result(0) == "read" and reads == [2]  # after the first command, before the next
    assert second.result(0) == 2
    assert [entry[3] for entry in log.seen if entry[0] == "before"] == [(1,), (2,)]
    inbox.close()
    with pytest.raises(ValueError, match="no door"):
        Inbox().submit_command(Command.call("pause"))


def test_the_control_commands_are_served_by_name_and_nothing_else_is() -> None:
    class Target:
        def __init__(self) -> None:
            self.calls: list[tuple[str, tuple[object, ...]]] = []

        def __getattr__(self, name: str) -> object:
            return lambda *args: self.calls.append((name, args)) or name

    door, target = Door(), Target()
    withdraw = serve(door, target, lambda c: [c.name])
    for name in COMMANDS:
        assert door.dispatch(Command.call(name, 1)) == name
    assert [name for name, _ in target.calls] == list(COMMANDS)
    assert door.dispatch(Command.line("time")) == ["time"]
    with pytest.raises(ConfigError, match="'plant_json' is not a control command"):
        door.dispatch(Command.call("plant_json"))
    withdraw()
    with pytest.raises(ConfigError, match="no line handler"):
        door.dispatch(Command.line("time"))


def _calls(path: Path, name: str) -> list[int]:
    tree = ast.parse(path.read_text("utf-8"))
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == name
    ]


def test_nothing_in_the_runtime_patches_live_objects_and_no_transport_is_ambient() -> None:
    patched = {
        str(p.relative_to(SRC)): lines
        for p in sorted((SRC / "runtime").rglob("*.py"))
        if (lines := _calls(p, "setattr"))
    }
    assert patched == {}
    ambient = [
        str(p.relative_to(SRC))
        for p in sorted((SRC / "transports").rglob("*.py"))
        if "ContextVar" in p.read_text("utf-8")
    ]
    assert ambient == []
