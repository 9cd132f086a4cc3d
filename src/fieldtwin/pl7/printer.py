"""Print a tree back to PL7-3 source (parse(print(tree)) == tree).

Parentheses are printed only where the precedence needs them: ``.`` ``*`` ``/``
``AND`` ``REM`` bind tighter than ``+`` ``-`` ``OR`` ``XOR``; NOT binds tightest.
"""

from __future__ import annotations

from fieldtwin.pl7 import tree as t

_UNARY = 3
_SPACED = {t.Op.WAND, t.Op.WOR, t.Op.WXOR, t.Op.REM}


def format_program(program: t.Program) -> str:
    lines: list[str] = []
    for section in program.sections:
        if isinstance(section, t.Literal):
            lines.append(f"%{section.name}")
            lines.extend(_sentences(section.sentences))
            lines.append("!EOP")
        else:
            lines.append("%CHART")
            for item in section.items:
                lines.extend(_chart_item(item))
    return "\n".join(lines) + "\n"


def _chart_item(item: t.ChartItem) -> list[str]:
    if isinstance(item, t.Comment):
        return [f"<{item.text}"]
    if isinstance(item, t.Initial):
        return ["CHART INITIAL " + ",".join(item.steps)]
    prefix = "CHART" if item.chart == t.MAIN else f"XM{item.chart}"
    if isinstance(item, t.Transition):
        return [f"{prefix} T: {item.source}>{item.target}", f"!     {format_expr(item.condition)}"]
    return [f"{prefix} S({item.kind}){item.step}", *_sentences(item.sentences)]


def _sentences(items: tuple[t.Sentence | t.Comment, ...]) -> list[str]:
    return [f"<{s.text}" if isinstance(s, t.Comment) else format_sentence(s) for s in items]


def format_sentence(sentence: t.Sentence) -> str:
    head = "!" if sentence.label is None else f"!L{sentence.label} :"
    body = ";".join(format_statement(s) for s in sentence.body)
    if not body:
        return head
    return f"{head}{body}" if sentence.label is not None else f"{head}     {body}"


def format_statement(statement: t.Statement) -> str:
    if isinstance(statement, t.If):
        text = f"IF {format_expr(statement.condition)} THEN {_actions(statement.then)}"
        if statement.otherwise is not None:
            text += f" ELSE {_actions(statement.otherwise)}"
        return text
    if isinstance(statement, t.While):
        return f"WHILE {format_expr(statement.condition)} DO {_actions(statement.body)}"
    return _action(statement)


def _actions(actions: tuple[t.Action, ...]) -> str:
    return ";".join(_action(a) for a in actions)


def _action(action: t.Action) -> str:
    if isinstance(action, t.Assign):
        return "->".join([format_expr(action.source), *map(format_expr, action.targets)])
    if isinstance(action, t.SetBit):
        return ("SET " if action.value else "RESET ") + format_expr(action.target)
    if isinstance(action, t.TxtOp):
        return f"{action.op} TXT{action.index}"
    if isinstance(action, t.Step):
        return ("INC " if action.up else "DEC ") + format_expr(action.target)
    if isinstance(action, t.Jump):
        return f"JUMP L{action.label}"
    if isinstance(action, t.Call):
        return f"CALL SR{action.sr}"
    return "RET"


def format_expr(node: t.Expr, context: int = 0) -> str:
    if isinstance(node, t.Binary):
        op = node.op
        sym = f" {op.symbol} " if op in _SPACED else op.symbol
        text = format_expr(node.left, op.level) + sym + format_expr(node.right, op.level + 1)
        return f"({text})" if op.level < context else text
    if isinstance(node, t.Not):
        return "NOT " + format_expr(node.operand, _UNARY)
    if isinstance(node, t.Compare):
        return f"[{format_expr(node.left)}{node.op}{format_expr(node.right)}]"
    if isinstance(node, t.Shift):
        return f"{'SHL' if node.left else 'SHR'} {node.count}({format_expr(node.operand)})"
    if isinstance(node, t.Edge):
        return f"{'RE' if node.rising else 'FE'}({format_expr(node.operand)})"
    if isinstance(node, t.Bta):
        return f"BTA({format_expr(node.operand)})"
    if isinstance(node, t.Const):
        return format_const(node)
    return format_object(node)


def format_const(node: t.Const) -> str:
    if node.radix is t.Radix.DEC:
        return str(node.value)
    if node.radix is t.Radix.TEXT:
        low, high = node.value & 0xFF, node.value >> 8
        return "M'" + chr(low) + (chr(high) if high else "") + "'"
    return f"{node.radix.value}'{node.value:X}'"


def format_object(node: t.Expr) -> str:
    if isinstance(node, t.Internal):
        return f"{node.kind}{node.index}"
    if isinstance(node, t.InternalBit):
        return f"{format_object(node.word)},{node.bit:X}"
    if isinstance(node, t.ModuleObj):
        return str(node.ref)
    if isinstance(node, t.TxtField):
        return f"TXT{node.index},{node.name}"
    if isinstance(node, t.Table):
        return f"{format_object(node.start)}[{node.length}]"
    if isinstance(node, t.Indexed):
        return f"{format_object(node.base)}({format_object(node.index)})"
    raise TypeError(f"not an object: {node!r}")
