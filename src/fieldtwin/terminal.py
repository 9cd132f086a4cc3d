"""The interactive console: line editing, history and help (cmd + readline).

Ctrl-C (docs/console.md): at the prompt it clears the line; while a command runs
it asks an ``advance`` to stop at its next step, with the plant kept as it
stands; a second Ctrl-C stops any command at once.  ``quit``, ``exit`` or
Ctrl-D leave.
"""

from __future__ import annotations

import cmd
import contextlib
import signal
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

from fieldtwin.console import HELP, Console
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant import Plant

HISTORY = Path.home() / ".fieldtwin_history"


class Interrupts:
    """Ctrl-C while a command runs: noted the first time, KeyboardInterrupt the second."""

    def __init__(self) -> None:
        self.pending = False

    def __call__(self) -> bool:
        return self.pending

    @contextlib.contextmanager
    def noting(self) -> Iterator[None]:
        self.pending = False
        previous = signal.signal(signal.SIGINT, self._note)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)
            self.pending = False

    def _note(self, signum: int, frame: FrameType | None) -> None:
        if self.pending:
            raise KeyboardInterrupt
        self.pending = True


class Terminal(cmd.Cmd):
    intro = "fieldtwin console. 'help' lists the commands, 'quit' leaves."
    prompt = "fieldtwin> "

    def __init__(self, console: Console, interrupts: Interrupts) -> None:
        super().__init__()
        self.console = console
        self.interrupts = interrupts

    def onecmd(self, line: str) -> bool:
        with self.interrupts.noting():
            try:
                return super().onecmd(line)
            except KeyboardInterrupt:
                print("interrupted")
                return False

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

    def run(self) -> None:
        """The command loop; Ctrl-C at the prompt drops the line and prompts again."""
        intro: str | None = self.intro
        while True:
            try:
                self.cmdloop(intro)
                return
            except KeyboardInterrupt:
                print("^C")
                intro = ""


def interactive(console: Console, plant: Plant) -> int:
    try:
        import readline

        with contextlib.suppress(OSError):
            readline.read_history_file(HISTORY)
    except ImportError:  # pragma: no cover - readline is on every Linux Python
        readline = None  # type: ignore[assignment]
    print(f"plant: {plant.title}")
    interrupts = Interrupts()
    console.interrupted = interrupts
    console.progress = lambda text: print(text, flush=True)
    Terminal(console, interrupts).run()
    if readline is not None:
        with contextlib.suppress(OSError):
            readline.write_history_file(HISTORY)
    return 0
