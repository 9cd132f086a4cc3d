"""The words of a console line: durations, numbers, objects, Text Block results.

Every parser here raises ConfigError naming the token and what is allowed
(docs/console.md); nothing else escapes.
"""

from __future__ import annotations

import shlex
from collections.abc import Iterator

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.addressing import format_object, parse_module, parse_object
from fieldtwin.tsx.txt import ExchangeResult
from fieldtwin.units import parse_duration as parse_duration  # the one value language
from fieldtwin.words import format_hex, parse_word


def integer(token: str, what: str) -> int:
    """A decimal (or 0x, H'..') count or number given on the command line."""
    try:
        return int(token, 0) if token.lower().startswith(("0x", "-0x")) else int(token, 10)
    except ValueError:
        if token.upper().startswith("H'"):
            return parse_word(token)
        raise ConfigError(f"{what}: {token!r} is not an integer") from None


def value_of(token: str) -> int | float | bool | str:
    for cast in (int, float):
        try:
            return cast(token)
        except ValueError:
            pass
    if token.lower() in ("true", "false"):
        return token.lower() == "true"
    return token


def result_lines(txt: int, result: ExchangeResult) -> list[str]:
    """The report line of a Text Block, then its data and text (docs/console.md)."""
    name = f"TXT{txt}"
    lines = [
        f"{name},{result.report_name} = {format_hex(result.v)}  {name},S = {result.s}"
        f"  {name},E = {int(result.e)}" + (f"  ({result.error_text})" if result.e else "")
    ]
    if result.data:
        lines.append("data = " + " ".join(format_hex(w) for w in result.words))
        printable = "".join(chr(b) if 32 <= b < 127 else "." for b in result.data)
        lines.append(f"text = {printable!r}")
    return lines


def latin1(text: str) -> bytes:
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError as exc:
        raise ConfigError(
            f"exchange text: {text[exc.start]!r} is not a character the module takes"
            " (allowed: ISO 8859-1)"
        ) from None


def split_line(line: str) -> list[str]:
    """Words, "quoted text" and # comments; H'00A0' keeps its apostrophes."""
    lexer = shlex.shlex(line, posix=True)
    lexer.quotes = '"'
    lexer.whitespace_split = True
    lexer.commenters = "#"
    return list(lexer)


def next_value(it: Iterator[str], token: str) -> str:
    try:
        return next(it)
    except StopIteration:
        raise ConfigError(f"exchange: {token!r} needs a value") from None


def one_argument(args: list[str], usage: str) -> str:
    if len(args) != 1:
        raise ConfigError(f"takes one argument: {usage}")
    return args[0]


def channel_number(token: str) -> int:
    try:
        return int(token, 0)
    except ValueError:
        raise ConfigError(f"{token!r} is not a channel number") from None


def module_address(token: str) -> tuple[int, int]:
    """'5' -> rack 0 slot 5; '23' -> rack 2 slot 3."""
    return parse_module(token)


def looks_like_object(token: str) -> bool:
    head = token.upper()
    return head.startswith(("IW", "OW", "I", "O", "W")) and any(ch.isdigit() for ch in head)


def canonical_name(name: str) -> str:
    if name.upper().startswith(("W", "B", "X", "CW", "SY", "SW")):  # internal objects
        return name.upper()
    return format_object(parse_object(name))
