"""`fieldtwin trace show FILE`: a traffic trace, one readable line per frame."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.trace import describe, matches, read_records
from fieldtwin.runtime.wiretap import FUNCTION_NAMES


def _function(text: str) -> int:
    """A function code (3, 0x03, 03) or its name (read_holding_registers)."""
    by_name = {name: code for code, name in FUNCTION_NAMES.items()}
    if text in by_name:
        return by_name[text]
    try:
        code = int(text, 0) if text.lower().startswith("0x") else int(text)
    except ValueError:
        code = -1
    if not 1 <= code <= 127:
        names = ", ".join(sorted(by_name))
        raise argparse.ArgumentTypeError(f"{text!r}: a function code 1..127 or one of {names}")
    return code


def _slave(text: str) -> int:
    try:
        number = int(text)
    except ValueError:
        number = -1
    if not 0 <= number <= 255:
        raise argparse.ArgumentTypeError(f"{text!r}: a slave number 0..255")
    return number


def add_parser(sub: Any) -> None:
    """Add ``trace show`` to the ``fieldtwin`` sub-commands."""
    examples = (
        "examples:\n"
        "  fieldtwin run plant.toml --trace traffic.jsonl --duration 30 --no-live\n"
        "  fieldtwin trace show traffic.jsonl --slave 2 --function 3\n"
        "  fieldtwin trace show traffic.jsonl --endpoint tcp://127.0.0.1:5020 | head"
    )
    raw = argparse.RawDescriptionHelpFormatter
    trace = sub.add_parser(
        "trace",
        help="read a traffic trace written by run --trace",
        formatter_class=raw,
        epilog=examples,
    )
    verbs = trace.add_subparsers(dest="verb", required=True)
    show = verbs.add_parser(
        "show", help="print a trace, one line per frame", formatter_class=raw, epilog=examples
    )
    show.add_argument("file", help="a JSON-lines trace (fieldtwin run --trace FILE)")
    show.add_argument("--endpoint", help="only this endpoint (as the plant file names it)")
    show.add_argument("--slave", type=_slave, help="only frames of this slave number")
    show.add_argument("--function", type=_function, help="only this function (3 or a name)")


def run_trace(args: argparse.Namespace) -> int:
    if args.verb != "show":
        raise ConfigError(f"trace {args.verb}: allowed: show")
    shown = 0
    for item in read_records(args.file):
        if matches(item, args.endpoint, args.slave, args.function):
            print(describe(item))
            shown += 1
    if shown == 0:
        print(f"{args.file}: no frame matches", file=sys.stderr)
    return 0


__all__ = ["add_parser", "run_trace"]
