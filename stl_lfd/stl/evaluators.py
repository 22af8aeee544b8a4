"""The evaluators of STL nodes: every node type compiles to an evaluator `(trace, start, stop)
-> B x (stop - start)` that computes the node's robustness at the samples [start, stop), with
the semantics' kernels (one function per node type, registered with `@_handles`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from stl_lfd.errors import SpecError
from stl_lfd.stl import ast
from stl_lfd.stl.printer import format_formula
from stl_lfd.stl.semantics import Semantics

# Sample times within this of a window's end belong to the window.
TIME_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Trace:
    """Signals of a batch of equally long traces, uniformly sampled."""

    signals: Mapping[str, np.ndarray]  # name -> B x T
    elapsed: np.ndarray  # T: times since the first sample
    batch: int
    shared: dict[tuple[int, int, int], np.ndarray] = field(default_factory=dict)  # values of shared nodes

    @property
    def length(self) -> int:
        return self.elapsed.size


Evaluator = Callable[[Trace, int, int], np.ndarray]


def _window(interval: ast.Interval | None, trace: Trace, start: int) -> tuple[int, int]:
    """First and last sample offsets covered by `interval` (the whole rest of the trace if None).

    Offsets are measured on the trace's own times from its first sample, so the window is exact
    at the first sample; uniform sampling makes the same offsets right at every other sample.
    An empty window comes back with last < first.
    """
    last = trace.length - 1 - start
    if interval is None:
        return 0, last
    lo = int(np.searchsorted(trace.elapsed, interval.lo - TIME_TOLERANCE, side="left"))
    hi = int(np.searchsorted(trace.elapsed, interval.hi + TIME_TOLERANCE, side="right")) - 1
    return lo, min(hi, last)


_COMPILERS: dict[type, Callable[[ast.Node, list[Evaluator], Semantics], Evaluator]] = {}


def _handles(node_type: type):
    def register(function):
        _COMPILERS[node_type] = function
        return function

    return register


@dataclass(frozen=True)
class Compiled:
    """What `compile_formula` finds in one pass over a formula."""

    evaluate: Evaluator
    depth: int  # levels of nesting
    horizon: float  # seconds
    signals: frozenset[str]


def compile_formula(formula: ast.Formula, semantics: Semantics) -> Compiled:
    """The evaluator of `formula`, built children first without recursion, each distinct node
    once (a node with several parents is wrapped to be computed once per range of samples),
    with the formula's depth, horizon and signals found on the way."""
    shared: set[int] = set()
    evaluators: dict[int, Evaluator] = {}
    extents: dict[int, tuple[int, float]] = {}  # id -> (depth, reach)
    signals: set[str] = set()
    for node in ast.post_order(formula, _parts, shared):
        try:
            compiler = _COMPILERS[type(node)]
        except KeyError:
            raise TypeError(f"cannot compile node of type {type(node).__name__}") from None
        key, parts = id(node), _parts(node)
        evaluator = compiler(node, [evaluators[id(part)] for part in parts], semantics)
        evaluators[key] = _computed_once(evaluator) if key in shared else evaluator
        if parts:
            operand_extents = [extents[id(part)] for part in parts]
            depth = ast.depth(node, [depth for depth, _ in operand_extents])
            extents[key] = (depth, ast.reach(node, [reach for _, reach in operand_extents]))
        elif type(node) is ast.Compare:  # a signal against a number: 2 levels, as `ast.depth` counts it
            signals.add(_signal_versus_number(node)[0])  # type: ignore[index]
            extents[key] = (2, 0.0)
        else:
            if type(node) is ast.Signal:
                signals.add(node.name)  # type: ignore[attr-defined]
            extents[key] = (1, 0.0)
    depth, reach = extents[id(formula)]
    return Compiled(evaluators[id(formula)], depth, reach, frozenset(signals))


def _parts(node: ast.Node) -> tuple[ast.Node, ...]:
    """The children the compiler needs: none for a comparison of a signal with a number, which
    compiles to one function (the commonest predicate, thousands of them in a large spec)."""
    return () if _signal_versus_number(node) is not None else node.children()


def _signal_versus_number(node: ast.Node) -> tuple[str, float, bool] | None:
    return node.signal_versus_number() if type(node) is ast.Compare else None


def _computed_once(evaluate: Evaluator) -> Evaluator:
    """`evaluate` for a node with several parents: each range of samples is computed once per
    trace. (No evaluator writes into the arrays its operands return.)"""

    def shared(trace: Trace, start: int, stop: int) -> np.ndarray:
        key = (id(shared), start, stop)
        if key not in trace.shared:
            trace.shared[key] = evaluate(trace, start, stop)
        return trace.shared[key]

    return shared


@_handles(ast.Const)
def _const(node: ast.Const, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    return lambda trace, start, stop: np.full((trace.batch, stop - start), node.value)


@_handles(ast.Signal)
def _signal(node: ast.Signal, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    return lambda trace, start, stop: trace.signals[node.name][:, start:stop]


@_handles(ast.Minus)
def _minus(node: ast.Minus, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    (operand,) = children
    return lambda trace, start, stop: -operand(trace, start, stop)


@_handles(ast.Abs)
def _abs(node: ast.Abs, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    (operand,) = children
    return lambda trace, start, stop: np.abs(operand(trace, start, stop))


_ARITHMETIC = {
    ast.ArithOp.ADD: np.add,
    ast.ArithOp.SUB: np.subtract,
    ast.ArithOp.MUL: np.multiply,
    ast.ArithOp.DIV: np.divide,
}


@_handles(ast.Arith)
def _arith(node: ast.Arith, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    (left, right), operation = children, _ARITHMETIC[node.op]

    def evaluate(trace: Trace, start: int, stop: int) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return operation(left(trace, start, stop), right(trace, start, stop))

    return evaluate


@_handles(ast.Compare)
def _compare(node: ast.Compare, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    greater = node.op in (ast.Comparator.GT, ast.Comparator.GE)
    simple = _signal_versus_number(node)
    if simple is not None:  # `signal - number` or `number - signal`, as the general case computes it
        name, number, signal_left = simple
        if greater == signal_left:
            return _finite_predicate(node, lambda trace, start, stop: trace.signals[name][:, start:stop] - number)
        return _finite_predicate(node, lambda trace, start, stop: number - trace.signals[name][:, start:stop])
    left, right = children if greater else reversed(children)
    return _finite_predicate(node, lambda trace, start, stop: left(trace, start, stop) - right(trace, start, stop))


@_handles(ast.InRange)
def _in_range(node: ast.InRange, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    (expr,) = children
    half_width, centre = (node.hi - node.lo) / 2, (node.hi + node.lo) / 2
    return _finite_predicate(node, lambda trace, start, stop: half_width - np.abs(expr(trace, start, stop) - centre))


def _finite_predicate(node: ast.Formula, evaluate: Evaluator) -> Evaluator:
    """`evaluate`, refusing infinite or NaN robustness (a division by zero or an overflow in
    the predicate's arithmetic), which would otherwise count as satisfied or poison the min."""

    def checked(trace: Trace, start: int, stop: int) -> np.ndarray:
        with np.errstate(all="ignore"):
            values = evaluate(trace, start, stop)
        if not np.all(np.isfinite(values)):
            sample = start + int(np.argwhere(~np.isfinite(values))[0][1])
            kind = "NaN" if np.isnan(values).any() else "infinite"
            raise SpecError(
                f"the predicate `{format_formula(node)}` is {kind} at t = {trace.elapsed[sample]:g} s (a division by zero or an overflow in its arithmetic)"
            )
        return values

    return checked


@_handles(ast.Not)
def _not(node: ast.Not, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    (child,) = children
    return lambda trace, start, stop: -child(trace, start, stop)


def _nary(values: list[np.ndarray], semantics: Semantics, sign: float) -> np.ndarray:
    """Conjunction (sign +1) or disjunction (sign -1) of the operands' values; a disjunction is
    `!(!a & !b & ...)`."""
    if sign > 0:
        return semantics.kernels.conjunction_of(values)
    return -semantics.kernels.conjunction_of([-value for value in values])


@_handles(ast.And)
@_handles(ast.Or)
def _and_or(node: ast.And | ast.Or, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    sign = 1.0 if isinstance(node, ast.And) else -1.0

    def evaluate(trace: Trace, start: int, stop: int) -> np.ndarray:
        values = []
        for operand in children:  # a loop, not a comprehension: one stack frame per level
            values.append(operand(trace, start, stop))
        return _nary(values, semantics, sign)

    return evaluate


@_handles(ast.Implies)
def _implies(node: ast.Implies, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    """`!a | b`."""
    left, right = children
    return lambda trace, start, stop: _nary([-left(trace, start, stop), right(trace, start, stop)], semantics, -1.0)


def _always_evaluator(child: Evaluator, interval: ast.Interval | None, semantics: Semantics, sign: float) -> Evaluator:
    """`G` (sign +1) or, as `!G!`, `F` (sign -1) over `interval`."""

    def evaluate(trace: Trace, start: int, stop: int) -> np.ndarray:
        lo, hi = _window(interval, trace, start)
        count = stop - start
        first, last = start + lo, min(stop - 1 + hi, trace.length - 1)
        if hi < lo or first > last:
            return np.full((trace.batch, count), sign * np.inf)
        values = sign * child(trace, first, last + 1)
        width = hi - lo + 1
        return sign * semantics.kernels.windows(values, width, count)

    return evaluate


@_handles(ast.Always)
def _always(node: ast.Always, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    return _always_evaluator(children[0], node.interval, semantics, 1.0)


@_handles(ast.Eventually)
def _eventually(node: ast.Eventually, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    return _always_evaluator(children[0], node.interval, semantics, -1.0)


@_handles(ast.Until)
def _until(node: ast.Until, children: list[Evaluator], semantics: Semantics) -> Evaluator:
    left, right = children

    def evaluate(trace: Trace, start: int, stop: int) -> np.ndarray:
        lo, hi = _window(node.interval, trace, start)
        count = stop - start
        last = min(stop - 1 + hi, trace.length - 1)
        if hi < lo or start + lo > last:
            return np.full((trace.batch, count), -np.inf)
        lefts, rights = left(trace, start, last + 1), right(trace, start, last + 1)
        return semantics.kernels.until(lefts, rights, lo, hi + 1, count)

    return evaluate
