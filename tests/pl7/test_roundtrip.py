"""Random well-formed programs print and parse back to the same tree (DESIGN rule 12),
and the three examples print and parse back to theirs."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.pl7 import check, format_program, parse
from fieldtwin.pl7 import tree as t
from fieldtwin.tsx.addressing import parse_object

from .helpers import EXAMPLES

small = st.integers(0, 40)
hexd = st.sampled_from("0123456789ABCDEF")


def module(kind: str) -> st.SearchStrategy[t.ModuleObj]:
    xy = st.sampled_from(["2", "5", "14", "23"])
    if kind in ("I", "O"):
        return st.builds(lambda m, b: t.ModuleObj(parse_object(f"{kind}{m},{b}")), xy, hexd)
    index = st.integers(0, 7).map(str)
    if kind in ("IWb", "OWb"):
        return st.builds(
            lambda m, i, b: t.ModuleObj(parse_object(f"{kind[:2]}{m},{i},{b}")), xy, index, hexd
        )
    return st.builds(lambda m, i: t.ModuleObj(parse_object(f"{kind}{m},{i}")), xy, index)


def internal(kind: str) -> st.SearchStrategy[t.Internal]:
    return small.map(lambda i: t.Internal(kind, i))


writable_bits = st.one_of(
    internal("B"),
    internal("SY"),
    module("O"),
    module("OWb"),
    st.builds(t.InternalBit, internal("W"), st.integers(0, 15)),
)
readable_bits = st.one_of(
    writable_bits,
    module("I"),
    module("IWb"),
    st.just(t.ModuleObj(parse_object("I5,S"))),
    st.builds(t.TxtField, st.integers(0, 9), st.sampled_from(["D", "E"])),
    internal("X"),
    internal("XM"),
)
writable_words = st.one_of(
    internal("W"),
    internal("SW"),
    module("OW"),
    st.builds(t.TxtField, st.integers(0, 9), st.sampled_from(["M", "C", "L"])),
    st.builds(t.Indexed, internal("W"), internal("W")),
)
readable_words = st.one_of(
    writable_words,
    internal("CW"),
    module("IW"),
    st.builds(t.TxtField, st.integers(0, 9), st.sampled_from(["V", "R", "S"])),
)
letters = st.sampled_from("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789?")
text_const = st.builds(
    lambda a, b: t.Const(ord(a) | (ord(b) << 8 if b else 0), t.Radix.TEXT),
    letters,
    st.one_of(st.just(""), letters),
)
constants = st.one_of(
    st.builds(
        t.Const, st.integers(0, 0xFFFF), st.sampled_from([t.Radix.DEC, t.Radix.HEX, t.Radix.B])
    ),
    text_const,
)
WORD_OPS = [op for op in t.Op if not op.on_bits]
words_ = st.recursive(
    st.one_of(readable_words, constants),
    lambda inner: st.one_of(
        st.builds(t.Binary, st.sampled_from(WORD_OPS), inner, inner),
        st.builds(t.Shift, st.booleans(), st.integers(0, 16), inner),
    ),
    max_leaves=6,
)
bits_ = st.recursive(
    st.one_of(
        readable_bits,
        st.builds(t.Compare, st.sampled_from(t.COMPARE_OPS), words_, words_),
        st.builds(t.Edge, st.booleans(), readable_bits),
    ),
    lambda inner: st.one_of(
        st.builds(t.Binary, st.sampled_from([t.Op.AND, t.Op.OR]), inner, inner),
        st.builds(t.Not, inner),
    ),
    max_leaves=6,
)
tables = st.one_of(
    st.builds(
        lambda i, n: (t.Table(t.Internal("W", i), n), t.Table(t.Internal("W", i + 50), n)),
        small,
        st.integers(1, 8),
    ),
    st.builds(
        lambda i, n: (t.Table(t.Internal("B", i), n), t.Table(t.Internal("B", i + 50), n)),
        small,
        st.integers(1, 8),
    ),
)
actions = st.one_of(
    st.builds(
        lambda s, ts: t.Assign(s, tuple(ts)), bits_, st.lists(writable_bits, min_size=1, max_size=3)
    ),
    st.builds(
        lambda s, ts: t.Assign(s, tuple(ts)),
        words_,
        st.lists(writable_words, min_size=1, max_size=3),
    ),
    tables.map(lambda pair: t.Assign(pair[0], (pair[1],))),
    st.builds(lambda w: t.Assign(w, (t.Table(t.Internal("W", 100), 3),)), words_),
    st.builds(lambda w: t.Assign(t.Bta(w), (t.Table(t.Internal("W", 160), 3),)), words_),
    st.builds(t.SetBit, writable_bits, st.booleans()),
    st.builds(t.Step, st.booleans(), writable_words),
    st.builds(t.TxtOp, st.sampled_from(["EXCHG", "INPUT", "OUTPUT", "RESET"]), st.integers(0, 9)),
    st.builds(t.Jump, st.integers(0, 5)),
    st.builds(t.Call, st.integers(0, 3)),
    st.just(t.Ret()),
)
action_lists = st.lists(actions, min_size=1, max_size=3).map(tuple)
statements = st.one_of(
    action_lists,
    st.builds(
        lambda c, a, b: (t.If(c, a, b),), bits_, action_lists, st.one_of(st.none(), action_lists)
    ),
    st.builds(lambda c, a: (t.While(c, a),), bits_, action_lists),
    st.just(()),
)
comments = st.text(st.characters(min_codepoint=32, max_codepoint=126), max_size=20).map(
    lambda s: t.Comment(s.rstrip())
)


@st.composite
def bodies(draw: st.DrawFn) -> tuple[t.Sentence | t.Comment, ...]:
    items: list[t.Sentence | t.Comment] = []
    labels = iter(draw(st.permutations(range(8))))
    for _ in range(draw(st.integers(0, 4))):
        if draw(st.booleans()) and draw(st.booleans()):
            items.append(draw(comments))
        label = next(labels) if draw(st.booleans()) else None
        items.append(t.Sentence(label, draw(statements)))
    return tuple(items)


@st.composite
def charts(draw: st.DrawFn) -> t.Chart:
    items: list[t.ChartItem] = [
        t.Initial(tuple(draw(st.lists(st.sampled_from(["0", "1", "M0"]), min_size=1, max_size=2))))
    ]
    for _ in range(draw(st.integers(0, 4))):
        chart = draw(st.sampled_from([t.MAIN, 0]))
        steps = ["0", "1", "2", "M0"] if chart == t.MAIN else ["IN", "0", "1", "OUT"]
        if draw(st.booleans()):
            items.append(
                t.Transition(
                    chart, draw(st.sampled_from(steps)), draw(st.sampled_from(steps)), draw(bits_)
                )
            )
        else:
            step = draw(st.sampled_from(steps))
            items.append(t.StepActions(chart, step, draw(st.sampled_from("AD")), draw(bodies())))
    return t.Chart(tuple(items))


@st.composite
def programs(draw: st.DrawFn) -> t.Program:
    sections: list[t.Section] = [t.Literal("PRE", draw(bodies()))]
    if draw(st.booleans()):
        sections.append(draw(charts()))
    if draw(st.booleans()):
        sections.append(t.Literal("POST", draw(bodies())))
    for n in draw(st.lists(st.integers(0, 3), unique=True, max_size=2)):
        sections.append(t.Literal(f"SR{n}", draw(bodies())))
    return t.Program(tuple(sections))


@settings(max_examples=300)
@given(programs())
def test_a_printed_program_parses_back_to_the_same_tree(program: t.Program) -> None:
    text = format_program(program)
    assert parse(text) == program, text


@pytest.mark.parametrize("name", ["aem811_tank.pl7", "dem24_assembly.pl7", "scm_exchange.pl7"])
def test_the_examples_print_and_parse_back(name: str) -> None:
    program = parse((EXAMPLES / name).read_text(), name)
    check(program, source=name)
    assert parse(format_program(program)) == program


def test_a_printed_example_prints_the_same_again(tmp_path: Path) -> None:
    program = parse((EXAMPLES / "dem24_assembly.pl7").read_text())
    once = format_program(program)
    assert format_program(parse(once)) == once
