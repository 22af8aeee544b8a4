"""Constant thresholds that a spec compares against, so that figures can draw them on the
signals: on single signals (`force < 2.0`, `shaft_tilt < 0.05`, `shaft_depth > 0.01`), and on
expressions of signals (`abs(box_x - shelf_x) < 0.01`, whose values `expression_values` gives)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Mapping

import numpy as np

from stl_lfd.stl import ast
from stl_lfd.stl.printer import format_formula


@dataclass(frozen=True)
class Threshold:
    """`signal op value`, read with the signal on the left (`2 > force` is `force < 2`); for a
    threshold on an expression of signals, `signal` is its text and `expression` the expression."""

    signal: str
    op: str
    value: float
    expression: ast.Expr | None = None

    def __str__(self) -> str:
        return f"{self.signal} {self.op} {self.value:g}"


FLIPPED = {"<": ">", "<=": ">=", ">": "<", ">=": "<="}


def signal_thresholds(spec: ast.Spec) -> dict[str, list[Threshold]]:
    """Signal name -> the distinct thresholds of the comparisons between that signal alone and a
    number in the spec's formula, through the definitions it uses; in the order first met."""
    return _grouped(threshold for node in _comparisons(spec) if (threshold := _threshold(node)) is not None)


def expression_thresholds(spec: ast.Spec) -> dict[str, list[Threshold]]:
    """Expression text -> the distinct thresholds of the comparisons between an expression of
    signals (not a signal alone) and a number (`abs(box_x - shelf_x) < 0.01`), as
    `signal_thresholds`."""
    return _grouped(threshold for node in _comparisons(spec) if (threshold := _expression_threshold(node)) is not None)


def expression_values(expression: ast.Expr, columns: Mapping[str, np.ndarray]) -> np.ndarray:
    """`T` values of `expression` on the signal `columns` (name -> `T` values)."""
    from stl_lfd.stl.evaluators import Trace, compile_formula
    from stl_lfd.stl.semantics import Semantics

    signals = {name: np.asarray(values, dtype=float)[None] for name, values in columns.items()}
    length = next(iter(signals.values())).shape[1]
    trace = Trace(signals, np.zeros(length), 1)
    return compile_formula(expression, Semantics("classic")).evaluate(trace, 0, length)[0]  # type: ignore[arg-type]


def _comparisons(spec: ast.Spec) -> Iterator[ast.Compare]:
    """The spec's comparisons, through the definitions it uses, in the order first met."""
    definitions = {definition.name: definition.formula for definition in spec.definitions}
    visited: set[str] = set()
    pending: list[ast.Node] = [spec.formula]
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Ref) and node.name in definitions and node.name not in visited:
            visited.add(node.name)
            pending.append(definitions[node.name])
        if isinstance(node, ast.Compare):
            yield node
        pending.extend(reversed(node.children()))


def _grouped(thresholds: Iterator[Threshold]) -> dict[str, list[Threshold]]:
    found: dict[str, list[Threshold]] = {}
    for threshold in thresholds:
        if threshold not in found.setdefault(threshold.signal, []):
            found[threshold.signal].append(threshold)
    return found


def _threshold(node: ast.Compare) -> Threshold | None:
    found = node.signal_versus_number()
    if found is None:
        return None
    signal, value, on_the_left = found
    return Threshold(signal, node.op.value if on_the_left else FLIPPED[node.op.value], value)


def _expression_threshold(node: ast.Compare) -> Threshold | None:
    for expression, number, on_the_left in ((node.left, node.right, True), (node.right, node.left, False)):
        if type(number) is ast.Const and type(expression) is not ast.Signal and any(type(each) is ast.Signal for each in ast.post_order(expression)):
            op = node.op.value if on_the_left else FLIPPED[node.op.value]
            return Threshold(format_formula(expression), op, number.value, expression)
    return None
