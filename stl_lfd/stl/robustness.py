"""Compile STL formulas into vectorised robustness functions.

    >>> from stl_lfd.stl import compile_spec, parse
    >>> robustness = compile_spec(parse("F[0, 1] x > 0.5"), semantics="classic")
    >>> robustness({"x": [0.0, 0.2, 0.9]}, times=[0.0, 0.5, 1.0])
    0.4

Every node compiles to an evaluator `(trace, start, stop) -> B x (stop - start)` that computes
the node's robustness only at the samples [start, stop); a temporal operator asks its operands
for just the samples its windows reach. The robustness of a trace is the value at its first
sample, so most of a long trace is never evaluated by formulas with bounded windows.

Compiling folds the formula without recursion, once per distinct node: a definition used in
several places is one shared node (see `resolve`), compiled once and, within one evaluation,
computed once per range of samples asked of it. Evaluating recurses, with at most two stack
frames a level of nesting, which the parser keeps within `MAX_DEPTH` (a formula built deeper in
code is refused here).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Callable, Iterator, Literal, Mapping

import numpy as np
from numpy.typing import ArrayLike

from stl_lfd.choices import SEMANTICS
from stl_lfd.errors import SignalError, SpecError, StlNameError
from stl_lfd.stl import ast
from stl_lfd.stl.kernels.semantics import KERNELS, Kernels
from stl_lfd.stl.parser import MAX_DEPTH, parse, resolve
from stl_lfd.stl.printer import format_formula

SemanticsName = Literal["classic", "new"]
# Sample times within this of a window's end belong to the window.
TIME_TOLERANCE = 1e-9
# Sampling counts as uniform when every step is within this fraction of the mean step.
UNIFORM_STEP_TOLERANCE = 0.01


class HorizonWarning(UserWarning):
    """A formula looks further ahead than the trace lasts; windows are clipped at its end."""


class CostWarning(UserWarning):
    """An evaluation will take long: the new robustness of a bounded `G`/`F` costs one n-ary
    conjunction per sample over its whole window, B x T x W operations for B traces. Given at
    most once per compiled spec."""


# Window operations of the new robustness per second on one core: 7e7 measured on a batch of 64
# traces of phi3_reorient (3,601 samples); machines differ up to 3x, so the estimate leans slow.
OPERATIONS_PER_SECOND = 5e7
# An evaluation estimated to take longer than this is announced, once per compiled spec.
COSTLY_SECONDS = 30.0


@dataclass(frozen=True)
class Semantics:
    """Which robustness to compute: `classic` space robustness or `new` with sharpness `nu`."""

    name: SemanticsName = "classic"
    nu: float = 1.0

    def __post_init__(self) -> None:
        if self.name not in SEMANTICS:
            raise SpecError(f"unknown semantics '{self.name}'; choose one of {', '.join(SEMANTICS)}")
        if not (math.isfinite(self.nu) and self.nu > 0):
            raise SpecError(f"nu must be a positive number (got {self.nu})")

    @property
    def kernels(self) -> Kernels:
        """What a conjunction, a window and an until are under this semantics."""
        return KERNELS[self.name](self.nu)


@dataclass(frozen=True)
class _Trace:
    """Signals of a batch of equally long traces, uniformly sampled."""

    signals: Mapping[str, np.ndarray]  # name -> B x T
    elapsed: np.ndarray  # T: times since the first sample
    batch: int
    shared: dict[tuple[int, int, int], np.ndarray] = field(default_factory=dict)  # values of shared nodes

    @property
    def length(self) -> int:
        return self.elapsed.size


Evaluator = Callable[[_Trace, int, int], np.ndarray]


class Robustness:
    """The robustness function of one formula under one semantics.

    Attributes:
        formula: the formula, with defined names inlined.
        semantics: the `Semantics` used.
        signals: names of the signals the formula reads.
        horizon: how far (s) the bounded windows look ahead of the first sample.
    """

    def __init__(self, formula: ast.Formula, semantics: Semantics, source: str = "<string>") -> None:
        self.formula = formula
        self.semantics = semantics
        self.source = source
        with ast.collector_paused():
            compiled = _compile(formula, semantics)
        if compiled.depth > MAX_DEPTH:
            raise SpecError(f"the formula nests more than {MAX_DEPTH} levels deep; simplify it", source)
        self.signals = compiled.signals
        self.horizon = compiled.horizon
        # The bounded `G`/`F` and their window lengths (s), for the cost warning of `_prepare`.
        self._windows = [
            (node, node.interval.hi - node.interval.lo)
            for node in (_distinct(formula) if semantics.name == "new" else ())
            if isinstance(node, (ast.Always, ast.Eventually)) and node.interval is not None
        ]
        self._warned_of_cost = False
        self._evaluate = compiled.evaluate

    def __call__(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> float | np.ndarray:
        """Robustness at the first sample.

        Args:
            signals: name -> `T` or `B x T` array (a batch of B traces of equal length).
            times: `T` sample times in seconds, uniformly spaced.

        Returns:
            a float for a single trace, a `B` array for a batch.
        """
        trace, batched = self._prepare(signals, times)
        values = self._located(trace, 0, 1)[:, 0]
        return values if batched else float(values[0])

    def trace(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> np.ndarray:
        """The robustness signal at every sample: `T` or `B x T`."""
        trace, batched = self._prepare(signals, times)
        values = self._located(trace, 0, trace.length)
        return values if batched else values[0]

    def _located(self, trace: _Trace, start: int, stop: int) -> np.ndarray:
        try:
            return self._evaluate(trace, start, stop)
        except SpecError as error:
            raise SpecError(error.message, self.source) from None

    def _prepare(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> tuple[_Trace, bool]:
        times = np.asarray(times, dtype=float)
        arrays = {name: np.asarray(signals[name], dtype=float) for name in self.signals if name in signals}
        missing = sorted(self.signals - arrays.keys())
        if missing:
            node = next(n for n in _distinct(self.formula) if isinstance(n, ast.Signal) and n.name == missing[0])
            available = ", ".join(sorted(signals)) or "none"
            raise StlNameError(f"unknown signal '{node.name}' (the trace has: {available})", node.source, node.line, node.column)
        _check_times(times)
        shapes = {array.shape for array in arrays.values()}
        if len(shapes) > 1 or any(array.ndim not in (1, 2) or array.shape[-1] != times.size for array in arrays.values()):
            raise SignalError(f"signals must all have shape (T,) or (B, T) with T = {times.size}; got {sorted(shapes)}")
        batched = any(array.ndim == 2 for array in arrays.values())
        batch = next(iter(shapes))[0] if batched else 1
        arrays = {name: array.reshape(batch, times.size) for name, array in arrays.items()}
        duration = float(times[-1] - times[0])
        if self.horizon > duration + TIME_TOLERANCE:
            warnings.warn(
                HorizonWarning(f"{self.source}: the formula looks {self.horizon:g} s ahead but the trace lasts {duration:g} s; windows are clipped at its end"),
                stacklevel=3,
            )
        self._warn_of_cost(times, batch)
        return _Trace(arrays, times - times[0], batch), batched

    def _warn_of_cost(self, times: np.ndarray, batch: int) -> None:
        """A CostWarning, the first time an evaluation is estimated to take over `COSTLY_SECONDS`."""
        if self.semantics.name != "new" or times.size < 2 or self._warned_of_cost:
            return
        step = float(times[-1] - times[0]) / (times.size - 1)
        windows = [(node, min(times.size, seconds / step + 1)) for node, seconds in self._windows]
        seconds = batch * times.size * sum(width for _, width in windows) / OPERATIONS_PER_SECOND
        if seconds > COSTLY_SECONDS:
            self._warned_of_cost = True
            node, width = max(windows, key=lambda item: item[1])
            traces = f"{batch} traces" if batch > 1 else "a trace"
            warnings.warn(
                CostWarning(
                    f"{self.source}: the new robustness of `{_shown(node)}` on {traces} of {times.size} samples takes about "
                    f"{seconds:.0f} s on one core (windows of up to {width:.0f} samples at every sample); the classic semantics "
                    "is linear in the samples"
                ),
                stacklevel=4,
            )


def compile_spec(spec: str | ast.Spec | ast.Formula, semantics: SemanticsName | Semantics = "classic", nu: float = 1.0, source: str = "<string>") -> Robustness:
    """Compile a specification (STL text, a parsed spec or a formula) into its robustness
    function."""
    if isinstance(spec, str):
        spec = parse(spec, source)
    if not isinstance(semantics, Semantics):
        semantics = Semantics(semantics, nu)
    formula = resolve(spec) if isinstance(spec, ast.Spec) else spec
    return Robustness(formula, semantics, source)


def horizon(node: ast.Node) -> float:
    """Seconds beyond the first sample that the bounded windows of `node` reach."""
    reach: dict[int, float] = {}
    for each in ast.post_order(node):
        interval = getattr(each, "interval", None)
        below = max([reach[id(child)] for child in each.children()], default=0.0)
        reach[id(each)] = below + interval.hi if interval is not None else below
    return reach[id(node)]


# --- Helper functions -----------------------------------------------------------------------


def _check_times(times: np.ndarray) -> None:
    if times.ndim != 1 or times.size == 0:
        raise SignalError("sample times must be a non-empty 1-D array")
    if times.size == 1:
        return
    steps = np.diff(times)
    if not np.all(steps > 0):
        index = int(np.argmax(steps <= 0)) + 1
        raise SignalError(f"sample times must be strictly increasing (sample {index}: t = {times[index]:g} s)")
    step = float(times[-1] - times[0]) / (times.size - 1)
    if np.max(np.abs(steps - step)) > UNIFORM_STEP_TOLERANCE * step:
        raise SignalError(f"sample times are not uniform (steps from {steps.min():g} to {steps.max():g} s); resample the signal")


def _window(interval: ast.Interval | None, trace: _Trace, start: int) -> tuple[int, int]:
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


def _distinct(formula: ast.Node) -> Iterator[ast.Node]:
    """Each node of `formula` once, depth first in the order of the text, however often it is
    shared."""
    seen: set[int] = set()
    stack = [formula]
    while stack:
        node = stack.pop()
        if id(node) not in seen:
            seen.add(id(node))
            yield node
            stack.extend(reversed(node.children()))


def _shown(node: ast.Node, most: int = 500) -> str:
    """`node` as text, or its operator alone when the text would spell out more than `most`
    nodes (shared definitions can make a small graph print as a huge formula)."""
    sizes: dict[int, int] = {}
    for each in ast.post_order(node):
        sizes[id(each)] = min(most + 1, 1 + sum(sizes[id(child)] for child in each.children()))
    if sizes[id(node)] <= most:
        return format_formula(node)
    interval = getattr(node, "interval", None)
    window = "" if interval is None else f"[{interval.lo:g}, {interval.hi:g}]"
    return f"{'G' if isinstance(node, ast.Always) else 'F'}{window} (...)"


_COMPILERS: dict[type, Callable[[ast.Node, list[Evaluator], Semantics], Evaluator]] = {}


def _handles(node_type: type):
    def register(function):
        _COMPILERS[node_type] = function
        return function

    return register


@dataclass(frozen=True)
class _Compiled:
    """What `_compile` finds in one pass over a formula."""

    evaluate: Evaluator
    depth: int  # levels of nesting
    horizon: float  # seconds
    signals: frozenset[str]


def _compile(formula: ast.Formula, semantics: Semantics) -> _Compiled:
    """The evaluator of `formula`, built children first without recursion, each distinct node
    once (a node with several parents is wrapped to be computed once per range of samples),
    with the formula's depth, horizon and signals found on the way."""
    shared: set[int] = set()
    evaluators: dict[int, Evaluator] = {}
    extents: dict[int, tuple[int, float]] = {}  # id -> (depth, horizon)
    signals: set[str] = set()
    for node in ast.post_order(formula, _parts, shared):
        try:
            compiler = _COMPILERS[type(node)]
        except KeyError:
            raise TypeError(f"cannot compile node of type {type(node).__name__}") from None
        parts = _parts(node)
        evaluator = compiler(node, [evaluators[id(part)] for part in parts], semantics)
        evaluators[id(node)] = _computed_once(evaluator) if id(node) in shared else evaluator
        if parts:
            depth, reach = max(extents[id(part)][0] for part in parts), max(extents[id(part)][1] for part in parts)
            interval = getattr(node, "interval", None)
            extents[id(node)] = (depth + 1, reach + interval.hi if interval is not None else reach)
        elif type(node) is ast.Compare:  # a signal against a number
            signals.add(_signal_versus_number(node)[0])  # type: ignore[index]
            extents[id(node)] = (2, 0.0)
        else:
            if type(node) is ast.Signal:
                signals.add(node.name)  # type: ignore[attr-defined]
            extents[id(node)] = (1, 0.0)
    depth, reach = extents[id(formula)]
    return _Compiled(evaluators[id(formula)], depth, reach, frozenset(signals))


def _parts(node: ast.Node) -> tuple[ast.Node, ...]:
    """The children the compiler needs: none for a comparison of a signal with a number, which
    compiles to one function (the commonest predicate, thousands of them in a large spec)."""
    return () if _signal_versus_number(node) is not None else node.children()


def _signal_versus_number(node: ast.Node) -> tuple[str, float, bool] | None:
    """(signal, number, signal on the left) of `x > 1` or `1 < x`, else None."""
    if type(node) is ast.Compare:
        left, right = node.left, node.right
        if type(left) is ast.Signal and type(right) is ast.Const:
            return left.name, right.value, True
        if type(left) is ast.Const and type(right) is ast.Signal:
            return right.name, left.value, False
    return None


def _computed_once(evaluate: Evaluator) -> Evaluator:
    """`evaluate` for a node with several parents: each range of samples is computed once per
    trace. (No evaluator writes into the arrays its operands return.)"""

    def shared(trace: _Trace, start: int, stop: int) -> np.ndarray:
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

    def evaluate(trace: _Trace, start: int, stop: int) -> np.ndarray:
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

    def checked(trace: _Trace, start: int, stop: int) -> np.ndarray:
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

    def evaluate(trace: _Trace, start: int, stop: int) -> np.ndarray:
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

    def evaluate(trace: _Trace, start: int, stop: int) -> np.ndarray:
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

    def evaluate(trace: _Trace, start: int, stop: int) -> np.ndarray:
        lo, hi = _window(node.interval, trace, start)
        count = stop - start
        last = min(stop - 1 + hi, trace.length - 1)
        if hi < lo or start + lo > last:
            return np.full((trace.batch, count), -np.inf)
        lefts, rights = left(trace, start, last + 1), right(trace, start, last + 1)
        return semantics.kernels.until(lefts, rights, lo, hi + 1, count)

    return evaluate
