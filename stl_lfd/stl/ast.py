"""Typed syntax tree of STL specifications.

Nodes are frozen dataclasses, so two trees compare equal when they have the same structure;
source positions (`line`, `column`, `source`) are kept for error messages but never compared.
Arithmetic expressions (`Expr`) produce real-valued signals; formulas (`Formula`) produce
robustness signals.
"""

from __future__ import annotations

import enum
import gc
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Iterator, Sequence


@dataclass(frozen=True)
class Interval:
    """Time window `[lo, hi]` in seconds relative to the evaluation time, `0 <= lo <= hi`."""

    lo: float
    hi: float


class Node:
    """Base of every syntax-tree node."""

    def children(self) -> tuple["Node", ...]:
        return ()


def _children(node: "Node") -> tuple["Node", ...]:
    return node.children()


def post_order(
    root: "Node",
    below: Callable[["Node"], tuple["Node", ...]] | None = None,
    shared: set[int] | None = None,
) -> list["Node"]:
    """The distinct nodes under `root` (itself included), each after all of its children,
    found without recursion.

    A node with several parents (in a graph made by `resolve`) comes once, and its id is added
    to `shared` if given. `below` replaces `Node.children` (e.g. to follow defined names).
    """
    below = below or _children
    order: list[Node] = []
    seen: set[int] = set()
    stack: list[Node | None] = [root]
    while stack:
        node = stack.pop()
        if node is None:  # all of the next node's children are in `order`
            order.append(stack.pop())  # type: ignore[arg-type]
        elif (key := id(node)) not in seen:
            seen.add(key)
            children = below(node)
            if children:
                stack += (node, None)
                stack += reversed(children)  # the first child comes out first
            else:
                order.append(node)
        elif shared is not None:
            shared.add(key)
    return order


def pre_order(root: "Node", below: Callable[["Node"], tuple["Node", ...]] | None = None) -> list["Node"]:
    """The distinct nodes under `root` (itself included), each before its children, in the
    order of the text: the order in which `post_order` first reaches them."""
    below = below or _children
    reached: list[Node] = []

    def recording(node: Node) -> tuple[Node, ...]:  # `post_order` asks once per distinct node
        reached.append(node)
        return below(node)

    post_order(root, recording)
    return reached


def depth(node: "Node", child_depths: Sequence[int]) -> int:
    """How many levels of operators `node` nests, given its children's depths: one more than
    the deepest (a leaf is 1 level, a predicate `x > 0` 2); a name (`Ref`) counts as deep as
    the definition it stands for, its one child when names are followed."""
    deepest = max(child_depths) if child_depths else 0  # `max(default=)` takes twice as long
    return deepest if type(node) is Ref else deepest + 1


def reach(node: "Node", child_reaches: Sequence[float]) -> float:
    """Seconds beyond the evaluation time that the bounded windows of `node` look, given its
    children's reaches."""
    furthest = max(child_reaches) if child_reaches else 0.0
    interval = getattr(node, "interval", None)
    return furthest + interval.hi if interval is not None else furthest


@contextmanager
def collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector paused while a large tree is built or compiled.

    The objects built (tokens, nodes, closures) hold no reference cycles, but each allocation
    counts towards the collector's next pass, and its full passes walk every live object: with
    them, compiling 330,000 predicates took three times as long.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


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

    def signal_versus_number(self) -> tuple[str, float, bool] | None:
        """(signal, number, whether the signal is on the left) of `x > 1` or `1 < x`, else None."""
        if type(self.left) is Signal and type(self.right) is Const:
            return self.left.name, self.right.value, True
        if type(self.left) is Const and type(self.right) is Signal:
            return self.right.name, self.left.value, False
        return None


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
        return self._formulas[name]

    @cached_property
    def _formulas(self) -> dict[str, Formula]:
        """name -> formula of every definition (the first, if a name were defined twice)."""
        formulas: dict[str, Formula] = {}
        for definition in self.definitions:
            formulas.setdefault(definition.name, definition.formula)
        return formulas
