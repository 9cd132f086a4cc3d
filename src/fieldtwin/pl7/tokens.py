"""The PL7-3 tokenizer: tokens with their line and column.

Line structure (AEM 5.1, DEM 5.3-4, SCM 4.6 listings): a line whose first
non-blank character is ``<`` is a comment; ``!`` starts a sentence; a line that
starts with neither continues the sentence above it (the manuals break long
sentences over several lines).  ``%NAME`` at the start of a line names a section
(our file format, docs/pl7.md).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from fieldtwin.pl7.errors import Pl7Error


class Kind(enum.Enum):
    IDENT = "identifier"
    NUMBER = "number"
    CONST = "constant"  # H'..' B'..' M'..'
    OP = "operator"
    BANG = "!"
    COMMENT = "comment"
    SECTION = "section header"
    END = "end of file"


@dataclass(frozen=True, slots=True)
class Token:
    kind: Kind
    text: str
    line: int
    column: int
    line_start: bool = False  # the first token on its line


# longest first
_OPERATORS = (
    *("->", "<>", "<=", ">=", "<", ">", "=", "+", "-", "*", "/", "."),
    *(",", ";", ":", "(", ")", "[", "]"),
)
_CONST_LETTERS = "HBM"
MAX_SOURCE = 1_000_000  # characters: a bound on what we read (DESIGN rule 14)


def tokenize(text: str, source: str = "") -> list[Token]:
    if len(text) > MAX_SOURCE:
        raise Pl7Error(1, 1, text[:10], f"a program of at most {MAX_SOURCE} characters", source)
    tokens: list[Token] = []
    for number, line in enumerate(text.splitlines(), start=1):
        _tokenize_line(line, number, tokens, source)
    lines = text.splitlines() or [""]
    tokens.append(Token(Kind.END, "", len(lines), len(lines[-1]) + 1, True))
    return tokens


def _tokenize_line(line: str, number: int, out: list[Token], source: str) -> None:
    stripped = line.lstrip()
    column = len(line) - len(stripped) + 1
    if not stripped:
        return
    if stripped[0] == "<":
        out.append(Token(Kind.COMMENT, stripped[1:].rstrip(), number, column, True))
        return
    if stripped[0] == "%":
        out.append(Token(Kind.SECTION, stripped[1:].strip(), number, column, True))
        return
    i = column - 1
    first = True
    n = len(line)
    while i < n:
        ch = line[i]
        if ch in " \t":
            i += 1
            continue
        start = i
        kind, i = _scan(line, i, number, source)
        text = line[start:i]
        if text == "→":
            text = "->"
        out.append(Token(kind, text, number, start + 1, first))
        first = False


def _scan(line: str, i: int, number: int, source: str) -> tuple[Kind, int]:
    ch = line[i]
    n = len(line)
    if ch == "!":
        return Kind.BANG, i + 1
    if ch == "→":
        return Kind.OP, i + 1
    if ch.upper() in _CONST_LETTERS and i + 1 < n and line[i + 1] == "'":
        end = line.find("'", i + 2)
        if end < 0:
            raise Pl7Error(number, i + 1, line[i:], "a closing ' after the constant", source)
        return Kind.CONST, end + 1
    if ch.isascii() and (ch.isalpha() or ch == "_"):
        j = i + 1
        while j < n and line[j].isascii() and (line[j].isalnum() or line[j] == "_"):
            j += 1
        return Kind.IDENT, j
    if ch.isascii() and ch.isdigit():
        j = i + 1
        while j < n and line[j].isascii() and line[j].isdigit():
            j += 1
        return Kind.NUMBER, j
    for op in _OPERATORS:
        if line.startswith(op, i):
            return Kind.OP, i + len(op)
    raise Pl7Error(number, i + 1, ch, "an object, a constant, a keyword or an operator", source)
