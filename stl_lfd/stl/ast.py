"""Typed syntax tree of STL specifications.

Nodes are frozen dataclasses, so two trees compare equal when they have the same structure;
source positions (`line`, `column`, `source`) are kept for error messages but never compared.
Arithmetic expressions (`Expr`) produce real-valued signals; formulas (`Formula`) produce
robustness signals.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Iterator


@dataclass(frozen=True)
class Interval:
    """Time window `[lo, hi]` in seconds relative to the evaluation time, `0 <= lo <= hi`."""

    lo: float
    hi: float


class Node:
    """Base of every syntax-tree node."""

    def children(self) -> tuple["Node", ...]:
        return ()

    def walk(self) -> Iterator["Node"]:
        """This node and all its descendants, depth first (without recursion, so that deep
        formulas cannot exhaust the stack)."""
        stack: list[Node] = [self]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children()))


# --- Arithmetic expressions ---------------------------------------------------------------


class Expr(Node):
    """A real-valued expression over signals."""


@dataclass(frozen=True)
class Const(Expr):
    value: float


@dataclass(frozen=True)
class Signal(Expr):
    """A column of the trace, e.g. `x` or `force`."""

    name: str
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)
    source: str = field(default="<string>", compare=False)


@dataclass(frozen=True)
class Minus(Expr):
    """Unary minus `-e`."""

    operand: Expr

    def children(self) -> tuple[Node, ...]:
        return (self.operand,)


class ArithOp(enum.Enum):
    ADD = "+"
    SUB = "-"
    MUL = "*"
    DIV = "/"


@dataclass(frozen=True)
class Arith(Expr):
    """Binary arithmetic `left op right`."""

    op: ArithOp
    left: Expr
    right: Expr

    def children(self) -> tuple[Node, ...]:
        return (self.left, self.right)


@dataclass(frozen=True)
class Abs(Expr):
    operand: Expr

    def children(self) -> tuple[Node, ...]:
        return (self.operand,)


# --- Formulas -------------------------------------------------------------------------------


class Formula(Node):
    """A formula whose robustness is a real-valued signal."""


class Comparator(enum.Enum):
    LT = "<"
    LE = "<="
    GT = ">"
    GE = ">="


@dataclass(frozen=True)
class Compare(Formula):
    """`left op right`; robustness `left - right` for > and >=, `right - left` for < and <=."""

    left: Expr
    op: Comparator
    right: Expr

    def children(self) -> tuple[Node, ...]:
        return (self.left, self.right)


@dataclass(frozen=True)
class InRange(Formula):
    """`expr in [lo, hi]`; robustness `(hi - lo)/2 - |expr - (hi + lo)/2|`."""

    expr: Expr
    lo: float
    hi: float

    def children(self) -> tuple[Node, ...]:
        return (self.expr,)


@dataclass(frozen=True)
class Ref(Formula):
    """A use of a defined formula name; `resolve` replaces it by the definition."""

    name: str
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)
    source: str = field(default="<string>", compare=False)


@dataclass(frozen=True)
class Not(Formula):
    child: Formula

    def children(self) -> tuple[Node, ...]:
        return (self.child,)


@dataclass(frozen=True)
class And(Formula):
    """n-ary conjunction: a chain `a & b & c` is one node with three children."""

    operands: tuple[Formula, ...]

    def children(self) -> tuple[Node, ...]:
        return self.operands


@dataclass(frozen=True)
class Or(Formula):
    """n-ary disjunction."""

    operands: tuple[Formula, ...]

    def children(self) -> tuple[Node, ...]:
        return self.operands


@dataclass(frozen=True)
class Implies(Formula):
    left: Formula
    right: Formula

    def children(self) -> tuple[Node, ...]:
        return (self.left, self.right)


@dataclass(frozen=True)
class Always(Formula):
    """`G[a,b] child`; without an interval, from now to the end of the trace."""

    child: Formula
    interval: Interval | None = None

    def children(self) -> tuple[Node, ...]:
        return (self.child,)


@dataclass(frozen=True)
class Eventually(Formula):
    """`F[a,b] child`; without an interval, from now to the end of the trace."""

    child: Formula
    interval: Interval | None = None

    def children(self) -> tuple[Node, ...]:
        return (self.child,)


@dataclass(frozen=True)
class Until(Formula):
    """`left U[a,b] right`: right holds at some t' in the window, left at every sample before."""

    left: Formula
    right: Formula
    interval: Interval | None = None

    def children(self) -> tuple[Node, ...]:
        return (self.left, self.right)


@dataclass(frozen=True)
class Definition:
    name: str
    formula: Formula
    line: int = field(default=0, compare=False)
    source: str = field(default="<string>", compare=False)


@dataclass(frozen=True)
class Spec:
    """A parsed specification file.

    Attributes:
        definitions: every `name := formula` in order, included files' first.
        formula: the specification (the last definition, or the bare formula at the end),
            still containing `Ref` nodes; `resolve(spec)` inlines them.
        name: the name of the last definition, or None for a bare formula.
    """

    definitions: tuple[Definition, ...]
    formula: Formula
    name: str | None = None

    def definition(self, name: str) -> Formula:
        for definition in self.definitions:
            if definition.name == name:
                return definition.formula
        raise KeyError(name)
