"""The interactive console: line editing, history and help (cmd + readline)."""

from __future__ import annotations

import cmd
import contextlib
from pathlib import Path

from fieldtwin.console import HELP, Console
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant import Plant

HISTORY = Path.home() / ".fieldtwin_history"


class Terminal(cmd.Cmd):
    intro = "fieldtwin console. 'help' lists the commands, 'quit' leaves."
    prompt = "fieldtwin> "

    def __init__(self, console: Console) -> None:
        super().__init__()
        self.console = console

    def default(self, line: str) -> None:
        try:
            for text in self.console.execute(line):
                print(text)
        except FieldtwinError as exc:
            print(f"error: {exc}")

    def do_exit(self, arg: str) -> bool:
        return True

    def do_help(self, arg: str) -> None:
        self.default(f"help {arg}")

    def do_quit(self, arg: str) -> bool:
        return True

    def do_EOF(self, arg: str) -> bool:  # noqa: N802 (cmd's own name)
        print()
        return True

    def emptyline(self) -> bool:
        return False

    def completenames(self, text: str, *ignored: object) -> list[str]:
        return [name for name in HELP if name.startswith(text)]


def interactive(console: Console, plant: Plant) -> int:
    try:
        import readline

        with contextlib.suppress(OSError):
            readline.read_history_file(HISTORY)
    except ImportError:  # pragma: no cover - readline is on every Linux Python
        readline = None  # type: ignore[assignment]
    print(f"plant: {plant.title}")
    try:
        Terminal(console).cmdloop()
    except KeyboardInterrupt:
        print()
    if readline is not None:
        with contextlib.suppress(OSError):
            readline.write_history_file(HISTORY)
    return 0
