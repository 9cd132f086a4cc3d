"""`fieldtwin trace show FILE`: a traffic trace, one readable line per frame, with the
register values a frame carries (written by a request, read by a reply)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping
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


VALUES_SHOWN = 16  # values printed per frame; the rest counted ("... 84 more")
_READ_BITS = frozenset((1, 2))
_READ_WORDS = frozenset((3, 4, 23))


def _pdu(item: Mapping[str, object]) -> bytes | None:
    """The frame's PDU (function code first) from its ``hex``: without the MBAP header
    (Modbus TCP) or the slave byte and CRC (RTU, RTU over TCP)."""
    text = item.get("hex")
    if not isinstance(text, str) or item.get("truncated"):
        return None
    try:
        data = bytes.fromhex(text)
    except ValueError:
        return None
    pdu = data[7:] if item.get("transport") == "tcp" else data[1:-2]
    return pdu if pdu else None


def _words(data: bytes) -> list[str]:
    return [f"H'{data[i] << 8 | data[i + 1]:04X}'" for i in range(0, len(data) - 1, 2)]


def _bits(data: bytes, count: int) -> list[str]:
    return [str(data[i // 8] >> (i % 8) & 1) for i in range(min(count, len(data) * 8))]


def _listed(head: str, shown: list[str]) -> str:
    more = len(shown) - VALUES_SHOWN
    text = f"{head} {' '.join(shown[:VALUES_SHOWN])}"
    return text + (f" ... {more} more" if more > 0 else "")


def frame_values(item: Mapping[str, object]) -> str:
    """``read H'0009' H'0000'`` (a reply to a read), ``write H'0001'`` (a write request),
    ``read 1 0 0 1`` (bits, the first address first); ``""`` for a frame without values
    (a read request, an exception, a line fault, a frame cut short)."""
    if item.get("kind") != "modbus" or "fault" in item or "error" in item:
        return ""
    if item.get("crc") == "bad" or item.get("exception") is not None:
        return ""
    pdu = _pdu(item)
    if pdu is None:
        return ""
    code, body = pdu[0], pdu[1:]
    count = item.get("count")
    count = count if isinstance(count, int) else 0
    try:
        if item.get("dir") == "out":
            if code in _READ_BITS | _READ_WORDS and (not body or len(body) < 1 + body[0]):
                return ""  # cut short: nothing invented
            if code in _READ_BITS:
                return _listed("read", _bits(body[1 : 1 + body[0]], count))
            if code in _READ_WORDS:
                return _listed("read", _words(body[1 : 1 + body[0]]))
            if code == 7 and body:
                return f"read status H'{body[0]:02X}'"
            return ""
        if code == 5 and len(body) >= 4:
            return "write " + ("1" if body[2] == 0xFF else "0")
        if code == 6 and len(body) >= 4:
            return _listed("write", _words(body[2:4]))
        if code == 15 and len(body) >= 5:
            return _listed("write", _bits(body[5 : 5 + body[4]], count))
        if code == 16 and len(body) >= 5:
            return _listed("write", _words(body[5 : 5 + body[4]]))
        if code == 23 and len(body) >= 9:
            return _listed("write", _words(body[9 : 9 + body[8]]))
    except IndexError:
        return ""
    return ""


def show_line(item: Mapping[str, object]) -> str:
    """The line ``trace show`` prints: the record described, then its values."""
    values = frame_values(item)
    line = describe(item)
    return f"{line}  {values}" if values else line


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
            print(show_line(item))
            shown += 1
    if shown == 0:
        print(f"{args.file}: no frame matches", file=sys.stderr)
    return 0


__all__ = ["add_parser", "frame_values", "run_trace", "show_line"]
