"""The PL7-3 parser: tokens -> the tree of fieldtwin.pl7.tree.

Expressions are typed while they are built: ``+`` is OR between bits and an
addition between words, and every operand, target and table length is checked
against its place.  Every refusal is a Pl7Error with line, column, token and
what was expected.
"""

from __future__ import annotations

import re
from difflib import get_close_matches

from fieldtwin.pl7 import tree as t
from fieldtwin.pl7.errors import Pl7Error
from fieldtwin.pl7.expressions import TXT_RE, ExpressionParser, assignable
from fieldtwin.pl7.tokens import Kind, Token, tokenize
from fieldtwin.pl7.types import BIT, WORD

_LABEL_RE = re.compile(r"^L(\d{1,3})$")
_SR_RE = re.compile(r"^SR(\d{1,3})$")
_MACRO_RE = re.compile(r"^XM(\d{1,2})$")
_STEP_RE = re.compile(r"^(\d{1,3}|M\d{1,2}|IN|OUT)$")
_ACTIONS = "an instruction (assignment ->, SET, RESET, INC, DEC, JUMP, CALL, RET, EXCHG)"


def parse(text: str, source: str = "") -> t.Program:
    """Parse a whole program file (sections ``%PRE``, ``%CHART``, ``%POST``, ``%SRi``)."""
    return _Parser(tokenize(text, source), source).program()


class _Parser(ExpressionParser):
    """Sections, the chart, sentences and instructions."""

    # --- program and sections ------------------------------------------------------

    def program(self) -> t.Program:
        sections: list[t.Section] = []
        leading: list[t.Comment] = []
        while self.tok.kind is Kind.COMMENT:
            leading.append(t.Comment(self.advance().text))
        if self.tok.kind not in (Kind.SECTION, Kind.END) or (leading and self.tok.kind is Kind.END):
            sections.append(self.literal("PRE", self.pos()))  # Literal only: the PRE
        while self.tok.kind is Kind.SECTION:
            tok = self.advance()
            name = tok.text.upper()
            if name == "CHART":
                sections.append(self.chart(self.pos(tok)))
            elif name in ("PRE", "POST") or _SR_RE.match(name):
                sections.append(self.literal(name, self.pos(tok)))
            else:
                self.fail("a section %PRE, %CHART, %POST or %SRi (i = 0..255)", tok)
        if self.tok.kind is not Kind.END:
            self.fail("a section header or the end of the file")
        if leading:  # comments above the first header belong to the first section
            sections[0] = _with_comments(sections[0], tuple(leading))
        return t.Program(tuple(sections))

    def literal(self, name: str, pos: t.Pos) -> t.Literal:
        self.in_chart = False
        items: list[t.Sentence | t.Comment] = []
        ended = False
        while self.tok.kind not in (Kind.SECTION, Kind.END):
            if self.tok.kind is Kind.COMMENT:
                items.append(t.Comment(self.advance().text))
            elif ended:
                self.fail("a comment or a section header after !EOP")
            elif self.tok.kind is Kind.BANG and self.ahead().text.upper() == "EOP":
                self.advance()
                self.advance()
                ended = True
            else:
                items.append(self.sentence())
        return t.Literal(name, tuple(items), pos)

    def chart(self, pos: t.Pos) -> t.Chart:
        self.in_chart = True
        items: list[t.ChartItem] = []
        chart = t.MAIN
        while self.tok.kind not in (Kind.SECTION, Kind.END):
            if self.tok.kind is Kind.COMMENT:
                items.append(t.Comment(self.advance().text))
                continue
            if not self.at_chart_header():
                self.fail("a step CHART S(A)n, a transition T: n>m or CHART INITIAL n")
            start = self.tok
            if self.is_word("CHART"):
                self.advance()
                chart = t.MAIN
            elif self.tok.kind is Kind.IDENT and _MACRO_RE.match(self.tok.text.upper()):
                chart, _ = self.numbered(_MACRO_RE, "XMj")
            items.append(self.chart_item(chart, start))
        return t.Chart(tuple(items), pos)

    def at_chart_header(self) -> bool:
        tok = self.tok
        if tok.kind is not Kind.IDENT or not tok.line_start:
            return False
        word = tok.text.upper()
        if word == "CHART" or _MACRO_RE.match(word):
            return True
        return word == "T" and self.ahead().kind is Kind.OP and self.ahead().text == ":"

    def chart_item(self, chart: int, start: Token) -> t.ChartItem:
        pos = self.pos(start)
        if self.is_word("INITIAL") and chart == t.MAIN:
            self.advance()
            steps = [self.step_name(chart)]
            while self.is_op(","):
                self.advance()
                steps.append(self.step_name(chart))
            return t.Initial(tuple(steps), pos)
        if self.is_word("T"):
            self.advance()
            self.expect_op(":")
            source = self.step_name(chart)
            self.expect_op(">", "'>' between the steps of a transition (T: n>m)")
            target = self.step_name(chart)
            return t.Transition(chart, source, target, self.condition(), pos)
        if self.is_word("S"):
            self.advance()
            self.expect_op("(")
            kind = self.tok.text.upper()
            if self.tok.kind is not Kind.IDENT or kind not in ("A", "D"):
                self.fail("A (actions on activation) or D (on deactivation)")
            self.advance()
            self.expect_op(")")
            step = self.step_name(chart)
            return t.StepActions(chart, step, kind, self.chart_body(), pos)
        self.fail("S(A)n, S(D)n, T: n>m" + (" or INITIAL" if chart == t.MAIN else ""))

    def step_name(self, chart: int) -> str:
        tok = self.tok
        text = tok.text.upper()
        if tok.kind not in (Kind.NUMBER, Kind.IDENT) or not _STEP_RE.match(text):
            where = "a step number" + (", Mj" if chart == t.MAIN else ", IN or OUT")
            self.fail(where)
        self.advance()
        return str(int(text)) if text.isdigit() else text

    def chart_body(self) -> tuple[t.Sentence | t.Comment, ...]:
        items: list[t.Sentence | t.Comment] = []
        while self.tok.kind in (Kind.COMMENT, Kind.BANG) and not self.at_chart_header():
            if self.tok.kind is Kind.COMMENT:
                items.append(t.Comment(self.advance().text))
            else:
                items.append(self.sentence())
        return tuple(items)

    def condition(self) -> t.Expr:
        if self.tok.kind is not Kind.BANG:
            self.fail("the transition's condition, a sentence '! condition'")
        self.advance()
        tok = self.tok
        node, typ = self.expr()
        if typ != BIT:
            self.fail("a bit condition (a transition's receptivity)", tok)
        if not self.at_sentence_end():
            self.fail("the end of the condition (one bit expression)")
        return node

    # --- sentences ------------------------------------------------------------------

    def at_sentence_end(self) -> bool:
        kind = self.tok.kind
        if kind in (Kind.BANG, Kind.COMMENT, Kind.SECTION, Kind.END):
            return True
        return self.in_chart and self.at_chart_header()

    def sentence(self) -> t.Sentence:
        bang = self.advance()
        label: int | None = None
        if (
            self.tok.kind is Kind.IDENT
            and _LABEL_RE.match(self.tok.text.upper())
            and self.ahead().text == ":"
        ):
            label, _ = self.numbered(_LABEL_RE, "a label Ln")
            self.advance()
        if self.is_word("EOP"):
            self.fail("an instruction (!EOP ends a Literal section, without a label)")
        body: tuple[t.Statement, ...]
        if self.is_word("IF"):
            body = (self.if_statement(),)
        elif self.is_word("WHILE"):
            body = (self.while_statement(),)
        else:
            body = self.actions(stop_at_else=False)
        if not self.at_sentence_end():
            self.fail("';' or the end of the sentence")
        return t.Sentence(label, body, self.pos(bang))

    def if_statement(self) -> t.If:
        self.advance()
        condition = self.bit_expr()
        self.expect_word("THEN")
        then = self.actions(stop_at_else=True)
        if not then:
            self.fail(_ACTIONS)
        otherwise = None
        if self.is_word("ELSE"):
            self.advance()
            otherwise = self.actions(stop_at_else=False)
            if not otherwise:
                self.fail(_ACTIONS)
        return t.If(condition, then, otherwise)

    def while_statement(self) -> t.While:
        self.advance()
        condition = self.bit_expr()
        self.expect_word("DO")
        body = self.actions(stop_at_else=False)
        if not body:
            self.fail(_ACTIONS)
        return t.While(condition, body)

    def bit_expr(self) -> t.Expr:
        tok = self.tok
        node, typ = self.expr()
        if typ != BIT:
            self.fail("a bit condition", tok)
        return node

    def actions(self, stop_at_else: bool) -> tuple[t.Action, ...]:
        out: list[t.Action] = []
        while not self.at_sentence_end() and not (stop_at_else and self.is_word("ELSE")):
            if self.is_word("IF") or self.is_word("WHILE"):
                self.fail("an instruction (IF and WHILE only start a sentence)")
            out.append(self.action())
            if not self.is_op(";"):
                break
            self.advance()
        return tuple(out)

    def action(self) -> t.Action:
        tok = self.tok
        word = tok.text.upper() if tok.kind is Kind.IDENT else ""
        if word == "JUMP":
            self.advance()
            label, at = self.numbered(_LABEL_RE, "a label Ln")
            return t.Jump(label, self.pos(at))
        if word == "CALL":
            self.advance()
            sr, at = self.numbered(_SR_RE, "a subroutine SRi")
            return t.Call(sr, self.pos(at))
        if word == "RET":
            self.advance()
            return t.Ret()
        if word in ("EXCHG", "INPUT", "OUTPUT"):
            self.advance()
            return self.txt_op(word)
        if word in ("SET", "RESET"):
            self.advance()
            is_txt = TXT_RE.match(self.tok.text.upper()) and self.ahead().text != ","
            if word == "RESET" and is_txt:
                return self.txt_op("RESET")
            return t.SetBit(self.bit_target(), word == "SET")
        if word in ("INC", "DEC"):
            self.advance()
            target_tok = self.tok
            node, typ = self.primary()
            if typ != WORD:
                self.fail("a word to count (Wi, SWi, OWxy,i, TXTi,M/C/L)", target_tok)
            self.check_writable(node, target_tok)
            return t.Step(word == "INC", node)
        if tok.kind is Kind.IDENT and word in _KEYWORDS_NOT_STARTING:
            self.fail(_ACTIONS)
        try:
            return self.assignment()
        except Pl7Error as err:
            near = get_close_matches(word, _INSTRUCTIONS, n=1, cutoff=0.6) if word else []
            if near and (err.line, err.column) == (tok.line, tok.column):  # not an object
                raise Pl7Error(
                    tok.line,
                    tok.column,
                    tok.text,
                    _ACTIONS,
                    self.source,
                    said=f"unknown instruction (did you mean {near[0]}?)",
                ) from None
            raise

    def txt_op(self, op: str) -> t.TxtOp:
        index, at = self.numbered(TXT_RE, "a Text Block TXTi")
        return t.TxtOp(op, index, self.pos(at))

    def bit_target(self) -> t.Expr:
        tok = self.tok
        node, typ = self.primary()
        if typ != BIT:
            self.fail("a bit to set or reset (Bi, SYi, Oxy,i, OWxy,i,j, Wi,j)", tok)
        self.check_writable(node, tok)
        return node

    def assignment(self) -> t.Assign:
        start = self.tok
        source, typ = self.expr()
        if not self.is_op("->"):
            self.fail("'->' (an assignment) or ';'" if self.tok != start else _ACTIONS)
        targets: list[t.Expr] = []
        while self.is_op("->"):
            self.advance()
            tok = self.tok
            node, target_type = self.primary()
            self.check_writable(node, tok)
            if not assignable(typ, target_type):
                self.fail(f"a target that takes {typ} (not {target_type})", tok)
            targets.append(node)
        return t.Assign(source, tuple(targets))


_KEYWORDS_NOT_STARTING = {"THEN", "ELSE", "DO", "EOP", "AND", "OR", "XOR", "REM"}
# what a misspelt first word of an action is compared with (a near miss is suggested)
_INSTRUCTIONS = (
    *("JUMP", "CALL", "RET", "EXCHG", "INPUT", "OUTPUT", "SET", "RESET", "INC", "DEC"),
    *("IF", "WHILE"),
)


def _with_comments(section: t.Section, comments: tuple[t.Comment, ...]) -> t.Section:
    if isinstance(section, t.Literal):
        return t.Literal(section.name, comments + section.sentences, section.pos)
    return t.Chart(comments + section.items, section.pos)
