"""Expressions and objects of PL7-3, typed while they are parsed (``+`` is OR
between bits and an addition between words); the token helpers the parser uses.

Every refusal is a Pl7Error with line, column, token and what was expected.

Depth is bounded (MAX_DEPTH): an expression nests at most that deep, counting each
parenthesis, bracket, NOT, RE/FE, SHL/SHR, BTA and index, and each operator over its
operands (a chain ``B0+B1+...`` is as deep as it is long).  The parser refuses
deeper text at the token that goes past the bound, before it recurses further, so
no program text ends in a RecursionError, and the compiled code stays within what
Python compiles (docs/pl7.md, "Bounds").
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import NoReturn

from fieldtwin.errors import ConfigError
from fieldtwin.objects import ObjectKind, parse_object
from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import Pl7Error
from fieldtwin.pl7.tokens import Kind, Token
from fieldtwin.pl7.types import BIT, WORD, Type, bits, words
from fieldtwin.words import parse_word

_INTERNAL_RE = re.compile(r"^(B|W|CW|SY|SW|X|XM)(\d{1,5})$")
_MODULE_RE = re.compile(r"^(IW|OW|I|O)(\d{1,2})$")
TXT_RE = re.compile(r"^TXT_?(\d{1,3})$")
_HEX_DIGIT = "0123456789ABCDEF"
_TEXT_TARGET = "an object to write (Bi, Wi, SYi, SWi, OWxy,i[,j], Oxy,i, TXTi,M/C/L, a table)"
_OBJECTS = "an object (Bi Wi CWi SYi SWi Xi IWxy,i[,j] OWxy,i[,j] Ixy,i Oxy,i Ixy,S TXTi,F)"
MAX_TABLE = 4096  # a table's length in the source (the internal words, tsx.txt.DATA_WORDS)
MAX_SHIFT = 16
MAX_DEPTH = 64  # how deep an expression nests (parentheses, NOT, operators): see above
_TOO_DEEP = f"an expression nested at most {MAX_DEPTH} deep (parentheses, NOT, operators)"


class ExpressionParser:
    """The token stream, expressions and objects; fieldtwin.pl7.parser adds the rest."""

    def __init__(self, tokens: list[Token], source: str) -> None:
        self.tokens = tokens
        self.i = 0
        self.source = source
        self.in_chart = False
        self.nesting = 0  # parentheses, brackets, NOT... open around the token
        self._depths: dict[int, int] = {}  # id(node) -> operators under it (a leaf: 0)

    # --- tokens ------------------------------------------------------------------

    @property
    def tok(self) -> Token:
        return self.tokens[self.i]

    def ahead(self, k: int = 1) -> Token:
        return self.tokens[min(self.i + k, len(self.tokens) - 1)]

    def advance(self) -> Token:
        tok = self.tokens[self.i]
        if tok.kind is not Kind.END:
            self.i += 1
        return tok

    def fail(self, expected: str, tok: Token | None = None) -> NoReturn:
        tok = tok or self.tok
        raise Pl7Error(tok.line, tok.column, tok.text, expected, self.source)

    def is_op(self, text: str) -> bool:
        return self.tok.kind is Kind.OP and self.tok.text == text

    def is_word(self, text: str) -> bool:
        return self.tok.kind is Kind.IDENT and self.tok.text.upper() == text

    def expect_op(self, text: str, expected: str | None = None) -> Token:
        if not self.is_op(text):
            self.fail(expected or f"'{text}'")
        return self.advance()

    def expect_word(self, text: str) -> Token:
        if not self.is_word(text):
            self.fail(text)
        return self.advance()

    def pos(self, tok: Token | None = None) -> t.Pos:
        tok = tok or self.tok
        return t.Pos(tok.line, tok.column)

    def numbered(self, pattern: re.Pattern[str], expected: str) -> tuple[int, Token]:
        tok = self.tok
        match = pattern.match(tok.text.upper()) if tok.kind is Kind.IDENT else None
        if match is None:
            self.fail(expected)
        self.advance()
        return int(match.group(1)), tok

    def check_writable(self, node: t.Expr, tok: Token) -> None:
        if not _writable(node):
            self.fail(_TEXT_TARGET, tok)

    # --- depth -----------------------------------------------------------------------

    def enter(self, tok: Token) -> None:
        """One level deeper (a parenthesis, NOT...), refused past MAX_DEPTH at ``tok``."""
        self.nesting += 1
        if self.nesting > MAX_DEPTH:
            self.fail(_TOO_DEEP, tok)

    def leave(self) -> None:
        self.nesting -= 1

    def deeper(self, node: t.Expr, tok: Token, *parts: t.Expr) -> t.Expr:
        """``node`` over ``parts``: one deeper than the deepest of them (refused past
        MAX_DEPTH at ``tok``)."""
        depth = 1 + max((self._depths.get(id(p), 0) for p in parts), default=0)
        if depth + self.nesting > MAX_DEPTH:
            self.fail(_TOO_DEEP, tok)
        self._depths[id(node)] = depth
        return node

    # --- expressions ------------------------------------------------------------------

    def expr(self) -> tuple[t.Expr, Type]:
        left, ltype = self.term()
        while True:
            op = self.binary_op(("+", "-"), ("OR", "XOR"))
            if op is None:
                return left, ltype
            left, ltype = self.combine(op, left, ltype, self.term)

    def term(self) -> tuple[t.Expr, Type]:
        left, ltype = self.unary()
        while True:
            op = self.binary_op((".", "*", "/"), ("AND", "REM"))
            if op is None:
                return left, ltype
            left, ltype = self.combine(op, left, ltype, self.unary)

    def binary_op(self, ops: tuple[str, ...], words_: tuple[str, ...]) -> Token | None:
        tok = self.tok
        if tok.kind is Kind.OP and tok.text in ops:
            return tok
        if tok.kind is Kind.IDENT and tok.text.upper() in words_:
            return tok
        return None

    def combine(
        self, op_tok: Token, left: t.Expr, ltype: Type, operand: Callable[[], tuple[t.Expr, Type]]
    ) -> tuple[t.Expr, Type]:
        self.advance()
        rtok = self.tok
        right, rtype = operand()
        symbol = op_tok.text.upper()
        op = _pick_op(symbol, ltype)
        if op is None:
            self.fail(f"an operator for {ltype} operands (not {symbol!r})", op_tok)
        want = BIT if op.on_bits else WORD
        if rtype != want:
            self.fail(f"a {want} operand after {symbol!r} (not {rtype})", rtok)
        return self.deeper(t.Binary(op, left, right), op_tok, left, right), want

    def unary(self) -> tuple[t.Expr, Type]:
        if self.is_word("NOT"):
            not_tok = self.advance()
            self.enter(not_tok)
            tok = self.tok
            operand, typ = self.unary()
            if typ != BIT:
                self.fail("a bit after NOT", tok)
            self.leave()
            return self.deeper(t.Not(operand), not_tok, operand), BIT
        return self.primary()

    def primary(self) -> tuple[t.Expr, Type]:
        tok = self.tok
        if tok.kind is Kind.OP and tok.text == "(":
            self.advance()
            self.enter(tok)
            node, typ = self.expr()
            self.expect_op(")", "')'")
            self.leave()
            return node, typ
        if tok.kind is Kind.OP and tok.text == "[":
            return self.comparison()
        if tok.kind is Kind.NUMBER:
            self.advance()
            return t.Const(_word_value(self, tok, int(tok.text)), t.Radix.DEC), WORD
        if tok.kind is Kind.CONST:
            self.advance()
            return _constant(self, tok), WORD
        if tok.kind is not Kind.IDENT:
            self.fail(_OBJECTS, tok)
        word = tok.text.upper()
        if word in ("RE", "FE"):
            return self.edge(word == "RE")
        if word in ("SHL", "SHR"):
            return self.shift(word == "SHL")
        if word == "BTA":
            self.advance()
            self.expect_op("(")
            self.enter(tok)
            operand = self.word_operand()
            self.expect_op(")")
            self.leave()
            return self.deeper(t.Bta(operand), tok, operand), words(3)
        return self.object()

    def comparison(self) -> tuple[t.Expr, Type]:
        self.enter(self.advance())
        left = self.word_operand()
        tok = self.tok
        if tok.kind is not Kind.OP or tok.text not in t.COMPARE_OPS:
            self.fail("a comparison = <> < > <= >=")
        self.advance()
        right = self.word_operand()
        self.expect_op("]", "']' closing the comparison")
        self.leave()
        return self.deeper(t.Compare(tok.text, left, right), tok, left, right), BIT

    def word_operand(self) -> t.Expr:
        tok = self.tok
        node, typ = self.expr()
        if typ != WORD:
            self.fail(f"a word (not {typ})", tok)
        return node

    def edge(self, rising: bool) -> tuple[t.Expr, Type]:
        self.advance()
        self.expect_op("(", "'(' after RE/FE")
        tok = self.tok
        node, typ = self.object()
        if typ != BIT or isinstance(node, t.Table):
            self.fail("a bit object inside RE()/FE()", tok)
        assert isinstance(node, t.Internal | t.InternalBit | t.ModuleObj | t.TxtField)
        self.expect_op(")", "')' after the edge's bit")
        return t.Edge(rising, node), BIT

    def shift(self, left: bool) -> tuple[t.Expr, Type]:
        self.advance()
        tok = self.tok
        if tok.kind is not Kind.NUMBER or not 0 <= int(tok.text) <= MAX_SHIFT:
            self.fail(f"a shift count 0..{MAX_SHIFT} (SHL n(...))")
        self.advance()
        self.enter(self.expect_op("(", "'(' after the shift count"))
        operand = self.word_operand()
        self.expect_op(")")
        self.leave()
        return self.deeper(t.Shift(left, int(tok.text), operand), tok, operand), WORD

    # --- objects ------------------------------------------------------------------------

    def object(self) -> tuple[t.Expr, Type]:
        tok = self.tok
        word = tok.text.upper()
        if TXT_RE.match(word):
            return self.txt_field()
        if _MODULE_RE.match(word):
            return self.module_object()
        match = _INTERNAL_RE.match(word)
        if match is None:
            self.fail(_OBJECTS)
        self.advance()
        obj = t.Internal(match.group(1), int(match.group(2)), self.pos(tok))
        if obj.kind in ("W", "CW", "SW") and self.is_op(","):
            self.advance()
            return t.InternalBit(obj, self.hex_digit("a bit 0..F of the word")), BIT
        if self.is_op("["):
            return self.table(obj, tok)
        if self.is_op("(") and obj.kind in ("W", "CW"):
            self.advance()
            itok = self.tok
            index, _ = self.object()
            if not isinstance(index, t.Internal) or index.kind != "W":
                self.fail("an index word Wi inside W(...)", itok)
            self.expect_op(")")
            return t.Indexed(obj, index, self.pos(tok)), WORD
        return obj, BIT if obj.is_bit else WORD

    def table(self, start: t.Internal | t.ModuleObj, tok: Token) -> tuple[t.Expr, Type]:
        self.advance()
        ntok = self.tok
        if ntok.kind is not Kind.NUMBER or not 1 <= int(ntok.text) <= MAX_TABLE:
            self.fail(f"a table length 1..{MAX_TABLE}")
        length = int(ntok.text)
        self.advance()
        self.expect_op("]", "']' after the table length")
        if isinstance(start, t.ModuleObj):
            ref = start.ref
            if ref.kind not in (ObjectKind.I, ObjectKind.O) or (ref.index or 0) + length > 16:
                self.fail("a bit string of the 16 discrete bits (Ixy,i[n], i + n <= 16)", ntok)
            return t.Table(start, length, self.pos(tok)), bits(length)
        if start.kind == "B":
            return t.Table(start, length, self.pos(tok)), bits(length)
        if start.kind in ("W", "CW"):
            return t.Table(start, length, self.pos(tok)), words(length)
        self.fail("a table of Bi, Wi or CWi", tok)

    def module_object(self) -> tuple[t.Expr, Type]:
        tok = self.advance()
        parts = [tok.text.upper()]
        count = 0
        while self.is_op(",") and count < 2:
            self.advance()
            part = self.tok
            if part.kind not in (Kind.NUMBER, Kind.IDENT) or len(part.text) != 1:
                self.fail("an index 0..F (or S for the fault bit)")
            parts.append(part.text.upper())
            self.advance()
            count += 1
        text = ",".join(parts)
        try:
            ref = parse_object(text)
        except ConfigError as err:
            self.fail(f"a module object ({err})", tok)
        obj = t.ModuleObj(ref)
        if self.is_op("["):
            return self.table(obj, tok)
        return obj, BIT if ref.is_bit else WORD

    def txt_field(self) -> tuple[t.Expr, Type]:
        index, tok = self.numbered(TXT_RE, "TXTi")
        self.expect_op(",", "',' and a Text Block field M C L V R S D E")
        field = self.tok.text.upper()
        if self.tok.kind is not Kind.IDENT or field not in t.TXT_WORD_FIELDS + t.TXT_BIT_FIELDS:
            self.fail("a Text Block field M C L V R S D E")
        self.advance()
        node = t.TxtField(index, field, self.pos(tok))
        return node, BIT if node.is_bit else WORD

    def hex_digit(self, expected: str) -> int:
        tok = self.tok
        text = tok.text.upper()
        if tok.kind not in (Kind.NUMBER, Kind.IDENT) or len(text) != 1 or text not in _HEX_DIGIT:
            self.fail(expected)
        self.advance()
        return _HEX_DIGIT.index(text)


def _pick_op(symbol: str, ltype: Type) -> t.Op | None:
    if ltype == BIT:
        return {"+": t.Op.OR, ".": t.Op.AND}.get(symbol)
    if ltype == WORD:
        table = {
            "+": t.Op.ADD,
            "-": t.Op.SUB,
            "*": t.Op.MUL,
            "/": t.Op.DIV,
            "REM": t.Op.REM,
            "AND": t.Op.WAND,
            "OR": t.Op.WOR,
            "XOR": t.Op.WXOR,
        }
        return table.get(symbol)
    return None


def assignable(source: Type, target: Type) -> bool:
    """What ``->`` may copy: a bit to a bit, a word to a word, a bit string or a table
    (filled), a bit string to a bit string or a word, a table to a table (same length)."""
    if source == target:
        return True
    if source == WORD:
        return target.kind in ("bits", "words") and (target.kind == "words" or target.n <= 16)
    if source.kind == "bits":
        return target == WORD and source.n <= 16
    return False


def _writable(node: t.Expr) -> bool:
    if isinstance(node, t.Internal):
        return node.kind in ("B", "W", "SY", "SW")
    if isinstance(node, t.InternalBit):
        return node.word.kind in ("W", "SW")
    if isinstance(node, t.ModuleObj):
        return node.ref.is_output
    if isinstance(node, t.TxtField):
        return node.name in t.TXT_WRITABLE
    if isinstance(node, t.Table):
        return _writable(node.start)
    if isinstance(node, t.Indexed):
        return node.base.kind == "W"
    return False


def _word_value(parser: ExpressionParser, tok: Token, value: int) -> int:
    if value > 0xFFFF:
        parser.fail("a word constant 0..65535", tok)
    return value


def _constant(parser: ExpressionParser, tok: Token) -> t.Const:
    letter, body = tok.text[0].upper(), tok.text[2:-1]
    if letter == "M":
        raw = body.encode("latin-1", "replace")
        if not 1 <= len(raw) <= 2:
            parser.fail("one or two characters in M'..'", tok)
        return t.Const(raw[0] | (raw[1] << 8 if len(raw) == 2 else 0), t.Radix.TEXT)
    if not 1 <= len(body) <= 4 or any(ch.upper() not in _HEX_DIGIT for ch in body):
        parser.fail(f"1 to 4 hex digits in {letter}'..' (H'0000'..H'FFFF')", tok)
    radix = t.Radix.HEX if letter == "H" else t.Radix.B
    return t.Const(parse_word(f"H'{body}'"), radix)
