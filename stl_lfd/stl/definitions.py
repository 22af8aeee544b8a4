"""The readable reference implementation of the robustness semantics: plain, obviously correct
evaluators, one sample at a time, straight from the definitions in DESIGN.md (docs/stl.md), no
vectorisation and no demand ranges. Far too slow for use; the compiled robustness and every
kernel of `stl_lfd.stl.kernels` are tested against it."""

from __future__ import annotations

import math

import numpy as np

from stl_lfd.stl import ast

TOLERANCE = 1e-9


def window(times: np.ndarray, k: int, interval: ast.Interval | None) -> list[int]:
    if interval is None:
        return list(range(k, len(times)))
    return [j for j in range(len(times)) if times[k] + interval.lo - TOLERANCE <= times[j] <= times[k] + interval.hi + TOLERANCE]


def expr(node: ast.Expr, signals: dict, k: int) -> float:
    match node:
        case ast.Const(value=value):
            return value
        case ast.Signal(name=name):
            return float(signals[name][k])
        case ast.Minus(operand=operand):
            return -expr(operand, signals, k)
        case ast.Abs(operand=operand):
            return abs(expr(operand, signals, k))
        case ast.Arith(op=op, left=left, right=right):
            a, b = expr(left, signals, k), expr(right, signals, k)
            return {"+": a + b, "-": a - b, "*": a * b, "/": a / b if b else math.copysign(math.inf, a) if a else math.nan}[op.value]
    raise TypeError(node)


def predicate(node: ast.Formula, signals: dict, k: int) -> float:
    if isinstance(node, ast.Compare):
        a, b = expr(node.left, signals, k), expr(node.right, signals, k)
        return a - b if node.op in (ast.Comparator.GT, ast.Comparator.GE) else b - a
    value = expr(node.expr, signals, k)
    return (node.hi - node.lo) / 2 - abs(value - (node.hi + node.lo) / 2)


def classic(node: ast.Formula, signals: dict, times: np.ndarray, k: int) -> float:
    """Space robustness at sample k."""
    return _robustness(node, signals, times, k, lambda values: min(values, default=math.inf))


def new(node: ast.Formula, signals: dict, times: np.ndarray, k: int, nu: float) -> float:
    """The new robustness at sample k, with the paper's conjunction written out per operand."""
    return _robustness(node, signals, times, k, lambda values: new_and(values, nu))


def new_and(values: list[float], nu: float) -> float:
    """The paper's conjunction, term by term, with DESIGN.md's rules for infinite operands."""
    if any(value == -math.inf for value in values):
        return -math.inf
    values = [value for value in values if value != math.inf]
    if not values:
        return math.inf
    rho_min = min(values)
    if rho_min == 0:
        return 0.0
    relative = [(value - rho_min) / rho_min for value in values]
    if rho_min < 0:
        numerator = sum(rho_min * math.exp(r) * math.exp(nu * r) for r in relative)
        return numerator / sum(math.exp(nu * r) for r in relative)
    numerator = sum(value * math.exp(-nu * r) for value, r in zip(values, relative))
    return numerator / sum(math.exp(-nu * r) for r in relative)


def _robustness(node, signals, times, k, conjunction) -> float:
    def rob(n, i):
        return _robustness(n, signals, times, i, conjunction)

    def disjunction(values):
        return -conjunction([-value for value in values])

    match node:
        case ast.Compare() | ast.InRange():
            return predicate(node, signals, k)
        case ast.Not(child=child):
            return -rob(child, k)
        case ast.And(operands=operands):
            return conjunction([rob(operand, k) for operand in operands])
        case ast.Or(operands=operands):
            return disjunction([rob(operand, k) for operand in operands])
        case ast.Implies(left=left, right=right):
            return disjunction([-rob(left, k), rob(right, k)])
        case ast.Always(child=child, interval=interval):
            return conjunction([rob(child, j) for j in window(times, k, interval)])
        case ast.Eventually(child=child, interval=interval):
            return disjunction([rob(child, j) for j in window(times, k, interval)])
        case ast.Until(left=left, right=right, interval=interval):
            return disjunction([conjunction([rob(right, j)] + [rob(left, i) for i in range(k, j)]) for j in window(times, k, interval)])
    raise TypeError(node)


def boolean(node: ast.Formula, signals: dict, times: np.ndarray, k: int) -> bool:
    """Qualitative semantics: a predicate holds when its value is > 0."""

    def holds(n, i):
        return boolean(n, signals, times, i)

    match node:
        case ast.Compare() | ast.InRange():
            return predicate(node, signals, k) > 0
        case ast.Not(child=child):
            return not holds(child, k)
        case ast.And(operands=operands):
            return all(holds(operand, k) for operand in operands)
        case ast.Or(operands=operands):
            return any(holds(operand, k) for operand in operands)
        case ast.Implies(left=left, right=right):
            return (not holds(left, k)) or holds(right, k)
        case ast.Always(child=child, interval=interval):
            return all(holds(child, j) for j in window(times, k, interval))
        case ast.Eventually(child=child, interval=interval):
            return any(holds(child, j) for j in window(times, k, interval))
        case ast.Until(left=left, right=right, interval=interval):
            return any(holds(right, j) and all(holds(left, i) for i in range(k, j)) for j in window(times, k, interval))
    raise TypeError(node)
