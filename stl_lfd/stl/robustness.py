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

import warnings
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.errors import SignalError, SpecError, StlNameError
from stl_lfd.stl import ast
from stl_lfd.stl.evaluators import TIME_TOLERANCE, Trace, compile_formula
from stl_lfd.stl.parser import MAX_DEPTH, parse, resolve
from stl_lfd.stl.printer import format_formula
from stl_lfd.stl.semantics import Semantics, SemanticsName

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
            compiled = compile_formula(formula, semantics)
        if compiled.depth > MAX_DEPTH:
            raise SpecError(f"the formula nests more than {MAX_DEPTH} levels deep; simplify it", source)
        self.signals = compiled.signals
        self.horizon = compiled.horizon
        # The bounded `G`/`F` and their window lengths (s), for the cost warning of `_prepare`.
        self._windows = [
            (node, node.interval.hi - node.interval.lo)
            for node in (ast.pre_order(formula) if semantics.name == "new" else ())
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

    def _located(self, trace: Trace, start: int, stop: int) -> np.ndarray:
        try:
            return self._evaluate(trace, start, stop)
        except SpecError as error:
            raise SpecError(error.message, self.source) from None

    def _prepare(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> tuple[Trace, bool]:
        times = np.asarray(times, dtype=float)
        arrays = {name: np.asarray(signals[name], dtype=float) for name in self.signals if name in signals}
        missing = sorted(self.signals - arrays.keys())
        if missing:
            node = next(n for n in ast.pre_order(self.formula) if isinstance(n, ast.Signal) and n.name == missing[0])
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
        return Trace(arrays, times - times[0], batch), batched

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


def compile_spec(
    spec: str | ast.Spec | ast.Formula, semantics: SemanticsName | Semantics = DEFAULT_SEMANTICS, nu: float = 1.0, source: str = "<string>"
) -> Robustness:
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
    reaches: dict[int, float] = {}
    for each in ast.post_order(node):
        reaches[id(each)] = ast.reach(each, [reaches[id(child)] for child in each.children()])
    return reaches[id(node)]


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
