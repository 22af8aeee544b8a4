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

A part that holds a disjunction always, `G[a, b] (A -> B)` or `G[a, b] (A | B)`, also has
*routes*: `G[a, b] B` and `G[a, b] !A` (or `G[a, b] A`, `G[a, b] B`), each of which implies the
part. While the part is violated its robustness can lead away from satisfaction (in
`G (HOLDER -> force < 2)`, pushing on the holder, it is the depth inside `HOLDER`, which is
least at the walls, away from the hole), and a route (`G force < 2`, the largest force) says
how far each trial was from satisfying it another way.

    >>> parts = split_spec(parse("F x > 0.5 & G (x > 1 -> y < 2)"))
    >>> [(route.part, route.name) for route in parts.routes]
    [(1, 'G !x > 1'), (1, 'G y < 2')]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.stl import ast
from stl_lfd.stl.parser import resolve
from stl_lfd.stl.printer import format_formula
from stl_lfd.stl.robustness import Robustness, compile_spec
from stl_lfd.stl.semantics import Semantics, SemanticsName


@dataclass(frozen=True)
class Route:
    """A formula that implies part `part` of a spec (see the module's docstring).

    Attributes:
        part: index of the part in `SpecParts.names`.
        name: the route's text.
        function: its robustness function, in the parts' semantics.
    """

    part: int
    name: str
    function: Robustness


@dataclass(frozen=True)
class SpecParts:
    """The top-level conjuncts of a specification and how they compose.

    Attributes:
        names: `m` texts of the conjuncts as written (defined names kept), unique.
        functions: `m` robustness functions, one per conjunct.
        semantics: the semantics of the functions and of `compose`.
        routes: formulas that each imply one of the parts (see the module's docstring).
    """

    names: tuple[str, ...]
    functions: tuple[Robustness, ...]
    semantics: Semantics
    routes: tuple[Route, ...] = ()

    @property
    def signals(self) -> frozenset[str]:
        """The signal names the parts read."""
        return frozenset().union(*(function.signals for function in self.functions))

    def __call__(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> np.ndarray:
        """`m` robustness values of the parts at the first sample (`B x m` for a batch)."""
        return np.stack([np.asarray(function(signals, times), dtype=float) for function in self.functions], axis=-1)

    def route_values(self, signals: Mapping[str, ArrayLike], times: ArrayLike) -> dict[str, float | np.ndarray]:
        """The robustness of each route (its text -> value) at the first sample (`B` values
        for a batch)."""
        return {route.name: route.function(signals, times) for route in self.routes}

    def compose(self, values: ArrayLike) -> float | np.ndarray:
        """The spec's robustness from its parts' values: `m` -> float, or `... x m` -> `...`."""
        values = np.asarray(values, dtype=float)
        composed = self.semantics.kernels.conjunction(values)
        return float(composed) if values.ndim == 1 else composed


def split_spec(spec: ast.Spec | ast.Formula, semantics: SemanticsName | Semantics = DEFAULT_SEMANTICS, nu: float = 1.0, source: str = "<string>") -> SpecParts:
    """The parts of `spec`: the operands of its top-level `&` (following defined names to it),
    or the whole formula when the top is not a conjunction."""
    if not isinstance(semantics, Semantics):
        semantics = Semantics(semantics, nu)
    spec = spec if isinstance(spec, ast.Spec) else ast.Spec((), spec)
    top = _follow(spec, spec.formula)
    operands = top.operands if isinstance(top, ast.And) else (top,)
    names = _unique([format_formula(operand) for operand in operands])
    functions = tuple(compile_spec(resolve(spec, operand), semantics, source=source) for operand in operands)
    routes = tuple(
        Route(index, format_formula(route), compile_spec(resolve(spec, route), semantics, source=source))
        for index, operand in enumerate(operands)
        for route in _routes(spec, operand)
    )
    return SpecParts(names, functions, semantics, routes)


def _routes(spec: ast.Spec, part: ast.Formula) -> list[ast.Formula]:
    """`G[a, b] D` for each disjunct `D` of a part `G[a, b] (D1 | D2 | ...)` (an implication
    `A -> B` is `!A | B`); none for other parts."""
    part = _follow(spec, part)
    if not isinstance(part, ast.Always):
        return []
    child = _follow(spec, part.child)
    if isinstance(child, ast.Implies):
        disjuncts = (ast.Not(child.left), child.right)
    elif isinstance(child, ast.Or):
        disjuncts = child.operands
    else:
        return []
    return [ast.Always(disjunct, part.interval) for disjunct in disjuncts]


def _follow(spec: ast.Spec, formula: ast.Formula) -> ast.Formula:
    """`formula` with defined names followed to what they stand for."""
    seen = set()
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
