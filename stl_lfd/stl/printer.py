"""Print syntax trees back as STL text that parses to the same tree.

Parentheses appear only where precedence or the n-ary grouping needs them: `(a & b) & c`
stays a nested conjunction, `a & b & c` one chain.
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
    text, _ = _format(node)
    return text


def _number(value: float) -> str:
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(float(value))


def _interval(interval: ast.Interval | None) -> str:
    return "" if interval is None else f"[{_number(interval.lo)}, {_number(interval.hi)}]"


def _format(node: ast.Node) -> tuple[str, int]:
    """(text, precedence level of the text's outermost operator)."""
    match node:
        case ast.Const(value=value):
            return _number(value), (_MINUS if value < 0 or str(value).startswith("-") else _ATOM)
        case ast.Signal(name=name) | ast.Ref(name=name):
            return name, _ATOM
        case ast.Abs(operand=operand):
            return f"abs({format_formula(operand)})", _ATOM
        case ast.Minus(operand=operand):
            return f"-{_wrap(operand, _MINUS)}", _MINUS
        case ast.Arith(op=op, left=left, right=right):
            level = _SUM if op in (ast.ArithOp.ADD, ast.ArithOp.SUB) else _PRODUCT
            return f"{_wrap(left, level)} {op.value} {_wrap(right, level + 1)}", level
        case ast.Compare(left=left, op=op, right=right):
            return f"{_wrap(left, _SUM)} {op.value} {_wrap(right, _SUM)}", _COMPARISON
        case ast.InRange(expr=expr, lo=lo, hi=hi):
            return f"{_wrap(expr, _SUM)} in [{_number(lo)}, {_number(hi)}]", _COMPARISON
        case ast.Not(child=child):
            return f"!{_wrap(child, _UNARY)}", _UNARY
        case ast.Always(child=child, interval=interval):
            return f"G{_interval(interval)} {_wrap(child, _UNARY)}", _UNARY
        case ast.Eventually(child=child, interval=interval):
            return f"F{_interval(interval)} {_wrap(child, _UNARY)}", _UNARY
        case ast.Until(left=left, right=right, interval=interval):
            return f"{_wrap(left, _UNARY)} U{_interval(interval)} {_wrap(right, _UNTIL)}", _UNTIL
        case ast.And(operands=operands):
            return " & ".join(_wrap(operand, _AND + 1) for operand in operands), _AND
        case ast.Or(operands=operands):
            return " | ".join(_wrap(operand, _OR + 1) for operand in operands), _OR
        case ast.Implies(left=left, right=right):
            return f"{_wrap(left, _OR)} -> {_wrap(right, _IMPLIES)}", _IMPLIES
    raise TypeError(f"cannot print node of type {type(node).__name__}")


def _wrap(node: ast.Node, minimum_level: int) -> str:
    """`node` as text, parenthesised if its operator binds looser than `minimum_level`."""
    text, level = _format(node)
    return text if level >= minimum_level else f"({text})"
