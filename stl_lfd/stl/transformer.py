"""The transformer Lark calls while it parses an STL specification: it builds the typed syntax
tree of `stl_lfd.stl.ast` rule by rule (no parse tree is kept), checking operand kinds and the
nesting limit as it goes (see `stl_lfd.stl.parser`)."""

from __future__ import annotations

import ast as python_ast
import math

from lark import Token, Transformer, v_args

from stl_lfd.errors import StlSyntaxError
from stl_lfd.stl import ast

# Operator nesting, counted through defined names (a predicate `x > 0` is 2 levels: the
# comparison and its operands); deeper specifications are refused. Real ones nest about 20.
MAX_DEPTH = 200


class Name:
    """A bare identifier: a signal in arithmetic, a formula reference in logic."""

    def __init__(self, name: str, line: int, column: int, source: str) -> None:
        self.name, self.line, self.column, self.source = name, line, column, source


class Part:
    """A piece of the specification on the parser's stack: its value (a syntax-tree node, a
    `Name`, an interval, a bound, ...), where its text starts (its opening parenthesis if it
    has one) and how deeply it nests operators (a name or a number counts 1)."""

    __slots__ = ("value", "line", "column", "depth")

    def __init__(self, value, line: int, column: int, depth: int = 0) -> None:
        self.value, self.line, self.column, self.depth = value, line, column, depth


# What a rule gets in place of an operand of the wrong kind, once the error is noted.
_NOT_A_FORMULA = ast.Compare(ast.Const(0.0), ast.Comparator.GT, ast.Const(0.0))
_NOT_AN_EXPRESSION = ast.Const(0.0)


@v_args(inline=True)
class ToAst(Transformer):
    """Builds the syntax tree while Lark parses: each method gets its rule's tokens and the
    `Part`s of its sub-rules, checks operand kinds and the nesting limit, and returns a `Part`.
    `start` returns (includes, definitions, final formula or None).

    Errors are noted, not raised, and parsing goes on, so that the errors come in the order of
    parsing the whole text first: a syntax error anywhere, else the first error here (rules
    are reduced in the order a transformer visits the tree), and the nesting limit last, after
    the names are checked.
    """

    # Set by `_parse_text` for each text:
    source = "<string>"
    error: StlSyntaxError | None = None  # the first error noted
    too_deep: tuple[int, int] | None = None  # (line, column) of the first operator past MAX_DEPTH
    uses_names = False  # whether a name is used as a formula

    def reset(self, source: str) -> None:
        self.source, self.error, self.too_deep, self.uses_names = source, None, None, False

    def start(self, *items: Part):
        includes = [item.value for item in items if isinstance(item.value, tuple)]
        definitions = [item.value for item in items if isinstance(item.value, ast.Definition)]
        formulas = [item for item in items if not isinstance(item.value, (tuple, ast.Definition))]
        formula = self._formula(formulas[0], items[0]) if formulas else None
        return includes, definitions, formula

    def include(self, keyword: Token, path: Token):
        return Part((python_ast.literal_eval(str(path)), keyword.line), keyword.line, keyword.column)

    def definition(self, name: Token, _assign: Token, body: Part):
        definition = ast.Definition(str(name), self._formula(body, name), name.line, self.source)
        return Part(definition, name.line, name.column, body.depth)

    def implies(self, left: Part, arrow: Token, right: Part):
        return self._node(ast.Implies(self._formula(left, left), self._formula(right, left)), left, arrow, (left, right))

    def disjunction(self, *items):
        operands = items[::2]
        return self._node(ast.Or(tuple(self._formula(operand, items[0]) for operand in operands)), items[0], items[1], operands)

    def conjunction(self, *items):
        operands = items[::2]
        return self._node(ast.And(tuple(self._formula(operand, items[0]) for operand in operands)), items[0], items[1], operands)

    def until(self, left: Part, keyword: Token, *rest: Part):
        interval, right = (rest[0].value, rest[1]) if len(rest) == 2 else (None, rest[0])
        return self._node(ast.Until(self._formula(left, left), self._formula(right, left), interval), left, keyword, (left, right))

    def negation(self, keyword: Token, child: Part):
        return self._node(ast.Not(self._formula(child, keyword)), keyword, keyword, (child,))

    def always(self, keyword: Token, *rest: Part):
        interval = rest[0].value if len(rest) == 2 else None
        return self._node(ast.Always(self._formula(rest[-1], keyword), interval), keyword, keyword, (rest[-1],))

    def eventually(self, keyword: Token, *rest: Part):
        interval = rest[0].value if len(rest) == 2 else None
        return self._node(ast.Eventually(self._formula(rest[-1], keyword), interval), keyword, keyword, (rest[-1],))

    def compare(self, left: Part, comparator: Token, right: Part):
        node = ast.Compare(self._expr(left, left), ast.Comparator(str(comparator)), self._expr(right, left))
        return self._node(node, left, comparator, (left, right))

    def region(self, expr: Part, keyword: Token, _open, lo: Part, _comma, hi: Part, _close):
        if lo.value > hi.value:
            self._note(f"empty range [{lo.value:g}, {hi.value:g}]: the lower end is above the upper", lo)
        return self._node(ast.InRange(self._expr(expr, expr), lo.value, hi.value), expr, keyword, (expr,))

    def arith(self, left: Part, op: Token, right: Part):
        return self._node(ast.Arith(ast.ArithOp(str(op)), self._expr(left, left), self._expr(right, left)), left, op, (left, right))

    def minus(self, sign: Token, operand: Part):
        value = self._expr(operand, sign)
        if isinstance(value, ast.Const):
            return Part(ast.Const(-value.value), sign.line, sign.column, operand.depth)
        return self._node(ast.Minus(value), sign, sign, (operand,))

    def absolute(self, keyword: Token, _open, operand: Part, _close):
        return self._node(ast.Abs(self._expr(operand, keyword)), keyword, keyword, (operand,))

    def group(self, bracket: Token, inner: Part, _close):
        return Part(inner.value, bracket.line, bracket.column, inner.depth)

    def number(self, token: Token):
        return Part(ast.Const(self._finite(token)), token.line, token.column, 1)

    def name(self, token: Token):
        return Part(Name(str(token), token.line, token.column, self.source), token.line, token.column, 1)

    def interval(self, bracket: Token, lo: Part, _comma, hi: Part, _close):
        for bound in (lo, hi):
            if bound.value < 0:
                self._note(f"interval bounds must be non-negative (got {bound.value:g})", bound)
        if lo.value > hi.value:
            self._note(f"empty interval [{lo.value:g}, {hi.value:g}]: the lower bound is above the upper", lo)
        return Part(ast.Interval(lo.value, hi.value), bracket.line, bracket.column)

    def bound(self, *tokens: Token):
        value = self._finite(tokens[-1]) * (-1.0 if str(tokens[0]) == "-" else 1.0)
        return Part(value, tokens[0].line, tokens[0].column)

    def _node(self, node: ast.Node, first: Part | Token, operator: Token, operands) -> Part:
        """`node` as a `Part` starting where `first` starts; the first operator to nest past
        `MAX_DEPTH` is noted."""
        depth = ast.depth(node, [operand.depth for operand in operands])
        if depth > MAX_DEPTH and self.too_deep is None:
            self.too_deep = (operator.line, operator.column)
        return Part(node, first.line, first.column, depth)

    def _note(self, message: str, at: Part | Token) -> None:
        if self.error is None:
            self.error = StlSyntaxError(message, self.source, at.line, at.column)

    def _finite(self, token: Token) -> float:
        value = float(token)
        if not math.isfinite(value):
            self._note(f"the number {token} is too large (at most about 1.8e308)", token)
            return 0.0
        return value

    def _formula(self, part: Part, at: Part | Token) -> ast.Formula:
        """The formula `part` holds; `at` (where the rule starts) places the error otherwise."""
        value = part.value
        if isinstance(value, Name):
            self.uses_names = True
            return ast.Ref(value.name, value.line, value.column, value.source)
        if isinstance(value, ast.Formula):
            return value
        self._note("expected a formula but found an arithmetic expression (missing a comparison such as > 0?)", at)
        return _NOT_A_FORMULA

    def _expr(self, part: Part, at: Part | Token) -> ast.Expr:
        value = part.value
        if isinstance(value, Name):
            return ast.Signal(value.name, value.line, value.column, value.source)
        if isinstance(value, ast.Expr):
            return value
        self._note("expected an arithmetic expression but found a formula", at)
        return _NOT_AN_EXPRESSION
