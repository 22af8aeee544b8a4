"""Print syntax trees back as STL text that parses to the same tree.

Parentheses appear only where precedence or the n-ary grouping needs them: `(a & b) & c`
stays a nested conjunction, `a & b & c` one chain.

Printing goes children first without recursion (`ast.post_order`), so any tree prints, and in
time linear in the length of its text.
"""

from __future__ import annotations

from stl_lfd.stl import ast

# Precedence levels, loosest first, as in stl.lark.
_IMPLIES, _OR, _AND, _UNTIL, _UNARY, _COMPARISON, _SUM, _PRODUCT, _MINUS, _ATOM = range(10)


def format_spec(spec: ast.Spec) -> str:
    """All definitions, one per line, then the bare formula if the spec has no name."""
    lines = [f"{definition.name} := {format_formula(definition.formula)}" for definition in spec.definitions]
    if spec.name is None:
        lines.append(format_formula(spec.formula))
    return "\n".join(lines) + "\n"


def format_formula(node: ast.Node) -> str:
    printed: dict[int, tuple[str, int]] = {}  # id -> (text, precedence level of its operator)
    for each in ast.post_order(node):
        printed[id(each)] = _format(each, [printed[id(child)] for child in each.children()])
    return printed[id(node)][0]


def _number(value: float) -> str:
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(float(value))


def _interval(interval: ast.Interval | None) -> str:
    return "" if interval is None else f"[{_number(interval.lo)}, {_number(interval.hi)}]"


def _format(node: ast.Node, children: list[tuple[str, int]]) -> tuple[str, int]:
    """(text, precedence level of the text's outermost operator) of `node`, given those of its
    children."""
    match node:
        case ast.Const(value=value):
            return _number(value), (_MINUS if value < 0 or str(value).startswith("-") else _ATOM)
        case ast.Signal(name=name) | ast.Ref(name=name):
            return name, _ATOM
        case ast.Abs():
            return f"abs({children[0][0]})", _ATOM
        case ast.Minus():
            return f"-{_wrap(children[0], _MINUS)}", _MINUS
        case ast.Arith(op=op):
            level = _SUM if op in (ast.ArithOp.ADD, ast.ArithOp.SUB) else _PRODUCT
            return f"{_wrap(children[0], level)} {op.value} {_wrap(children[1], level + 1)}", level
        case ast.Compare(op=op):
            return f"{_wrap(children[0], _SUM)} {op.value} {_wrap(children[1], _SUM)}", _COMPARISON
        case ast.InRange(lo=lo, hi=hi):
            return f"{_wrap(children[0], _SUM)} in [{_number(lo)}, {_number(hi)}]", _COMPARISON
        case ast.Not():
            return f"!{_wrap(children[0], _UNARY)}", _UNARY
        case ast.Always(interval=interval):
            return f"G{_interval(interval)} {_wrap(children[0], _UNARY)}", _UNARY
        case ast.Eventually(interval=interval):
            return f"F{_interval(interval)} {_wrap(children[0], _UNARY)}", _UNARY
        case ast.Until(interval=interval):
            return f"{_wrap(children[0], _UNARY)} U{_interval(interval)} {_wrap(children[1], _UNTIL)}", _UNTIL
        case ast.And():
            return " & ".join([_wrap(child, _AND + 1) for child in children]), _AND
        case ast.Or():
            return " | ".join([_wrap(child, _OR + 1) for child in children]), _OR
        case ast.Implies():
            return f"{_wrap(children[0], _OR)} -> {_wrap(children[1], _IMPLIES)}", _IMPLIES
    raise TypeError(f"cannot print node of type {type(node).__name__}")


def _wrap(printed: tuple[str, int], minimum_level: int) -> str:
    """A printed node, parenthesised if its operator binds looser than `minimum_level`."""
    text, level = printed
    return text if level >= minimum_level else f"({text})"
