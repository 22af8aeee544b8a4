"""A specification split at its top-level conjunction, for optimisers that model each part.

    >>> from stl_lfd.stl import parse, split_spec
    >>> parts = split_spec(parse("F[0, 1] x > 0.5 & G x < 2"), semantics="classic")
    >>> parts.names
    ('F[0, 1] x > 0.5', 'G x < 2')
    >>> values = parts({"x": [0.0, 0.2, 0.9]}, times=[0.0, 0.5, 1.0])
    >>> values, parts.compose(values)
    (array([0.4, 1.1]), 0.4)

The robustness of `a & b & c` is a fixed function of the robustness of a, b and c (their
minimum, or the n-ary conjunction of the new robustness), so `compose` of the parts' values is
exactly the spec's robustness. A spec that is not a conjunction at the top is one part.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike

from stl_lfd.stl import ast
from stl_lfd.stl.printer import format_formula
from stl_lfd.stl.robustness import Robustness, Semantics, SemanticsName, compile_spec


@dataclass(frozen=True)
class SpecParts:
    """The top-level conjuncts of a specification and how they compose.

    Attributes:
        names: `m` texts of the conjuncts as written (defined names kept), unique.
        functions: `m` robustness functions, one per conjunct.
        semantics: the semantics of the functions and of `compose`.
    """

    names: tuple[str, ...]
    functions: tuple[Robustness, ...]
    semantics: Semantics

    @property
    def signals(self) -> frozenset[str]:
        """The signal names the parts read."""
        return frozenset().union(*(function.signals for function in self.functions))

    def __call__(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> np.ndarray:
        """`m` robustness values of the parts at the first sample (`B x m` for a batch)."""
        return np.stack([np.asarray(function(signals, times), dtype=float) for function in self.functions], axis=-1)

    def compose(self, values: ArrayLike) -> float | np.ndarray:
        """The spec's robustness from its parts' values: `m` -> float, or `... x m` -> `...`."""
        values = np.asarray(values, dtype=float)
        composed = self.semantics.conjunction(values, self.semantics.nu)
        return float(composed) if values.ndim == 1 else composed


def split_spec(spec: ast.Spec | ast.Formula, semantics: SemanticsName | Semantics = "classic", nu: float = 1.0, source: str = "<string>") -> SpecParts:
    """The parts of `spec`: the operands of its top-level `&` (following defined names to it),
    or the whole formula when the top is not a conjunction."""
    if not isinstance(semantics, Semantics):
        semantics = Semantics(semantics, nu)
    spec = spec if isinstance(spec, ast.Spec) else ast.Spec((), spec)
    top = _follow_names(spec)
    operands = top.operands if isinstance(top, ast.And) else (top,)
    names = _unique([format_formula(operand) for operand in operands])
    functions = tuple(compile_spec(replace(spec, formula=operand), semantics, source=source) for operand in operands)
    return SpecParts(names, functions, semantics)


def _follow_names(spec: ast.Spec) -> ast.Formula:
    formula, seen = spec.formula, set()
    while isinstance(formula, ast.Ref) and formula.name not in seen:
        seen.add(formula.name)
        formula = spec.definition(formula.name)
    return formula


def _unique(names: list[str]) -> tuple[str, ...]:
    """Repeated conjuncts get `#2`, `#3`... so that each part has its own key."""
    counts: dict[str, int] = {}
    unique = []
    for name in names:
        counts[name] = counts.get(name, 0) + 1
        unique.append(name if counts[name] == 1 else f"{name} #{counts[name]}")
    return tuple(unique)
