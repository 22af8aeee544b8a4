"""Hypothesis strategies: random formulas over signals x and y, random uniform traces."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from stl_lfd.stl import ast

SIGNALS = ("x", "y")
STEPS = (0.1, 0.25, 0.5, 1.0)

signal = st.sampled_from(SIGNALS).map(ast.Signal)
constant = st.integers(-8, 8).map(lambda n: ast.Const(n / 8))


def expressions() -> st.SearchStrategy[ast.Expr]:
    return st.one_of(
        signal,
        signal,
        st.builds(ast.Arith, st.sampled_from([ast.ArithOp.ADD, ast.ArithOp.SUB, ast.ArithOp.MUL]), signal, st.one_of(signal, constant)),
        st.builds(ast.Abs, signal),
        st.builds(ast.Minus, signal),
    )


predicates = st.one_of(
    st.builds(ast.Compare, expressions(), st.sampled_from(list(ast.Comparator)), constant),
    st.builds(
        lambda e, lo, width: ast.InRange(e, lo / 8, (lo + width) / 8),
        expressions(),
        st.integers(-8, 6),
        st.integers(0, 8),
    ),
)

intervals = st.one_of(
    st.none(),
    st.builds(lambda lo, width: ast.Interval(lo / 4, (lo + width) / 4), st.integers(0, 12), st.integers(0, 12)),
)


def _compound(children: st.SearchStrategy[ast.Formula]) -> st.SearchStrategy[ast.Formula]:
    operand_lists = st.lists(children, min_size=2, max_size=3).map(tuple)
    return st.one_of(
        st.builds(ast.Not, children),
        st.builds(ast.And, operand_lists),
        st.builds(ast.Or, operand_lists),
        st.builds(ast.Implies, children, children),
        st.builds(ast.Always, children, intervals),
        st.builds(ast.Eventually, children, intervals),
        st.builds(ast.Until, children, children, intervals),
    )


formulas = st.recursive(predicates, _compound, max_leaves=6)


@st.composite
def traces(draw, batch: int | None = None, max_length: int = 24):
    """(signals, times): signals name -> T (or B x T) array with values in [-1, 1]."""
    length = draw(st.integers(1, max_length))
    step = draw(st.sampled_from(STEPS))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    shape = (length,) if batch is None else (batch, length)
    # Values on a 1/64 grid keep ties (and exact zeros) possible but rare.
    signals = {name: np.round(rng.uniform(-1, 1, size=shape) * 64) / 64 + 1 / 128 for name in SIGNALS}
    start = draw(st.sampled_from([0.0, 3.0]))
    return signals, start + step * np.arange(length)
