"""Parse STL specification text into the typed syntax tree of `stl_lfd.stl.ast`.

Entry points: `parse(text, source)` for text, `load_spec(path)` for files (which also follows
`include` lines), and `resolve(spec)` to inline defined names into one formula.
"""

from __future__ import annotations

import ast as python_ast
import math
from functools import cache
from pathlib import Path

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from stl_lfd.dag import fold
from stl_lfd.errors import SpecError, StlNameError, StlSyntaxError, caret_context
from stl_lfd.files import UnreadableFile, read_text
from stl_lfd.stl import ast

_READABLE_TERMINALS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "COMPARATOR": "a comparison (< <= > >=)",
    "ESCAPED_STRING": "a quoted file name",
    "$END": "end of input",
}


@cache
def _parser() -> Lark:
    return Lark.open("stl.lark", rel_to=__file__, parser="lalr", propagate_positions=True, cache=True)


def parse(text: str, source: str = "<string>", base_dir: Path | None = None) -> ast.Spec:
    """Parse a specification.

    Args:
        text: the specification text.
        source: name used in error messages (usually the file path).
        base_dir: folder that `include` paths are relative to (default: the current folder).

    Returns:
        The `Spec`, with definitions checked: no duplicates, no undefined or recursive names.

    Raises:
        StlSyntaxError, StlNameError: with line, column and a caret under the offending text.
    """
    return _parse(text, source, base_dir or Path.cwd(), including=())


def load_spec(path: str | Path) -> ast.Spec:
    """Read and parse a specification file (see `parse`)."""
    path = Path(path)
    return _parse(_read(path, str(path)), str(path), path.parent, including=())


def resolve(spec: ast.Spec) -> ast.Formula:
    """The specification formula with every defined name replaced by its definition."""
    definitions = {definition.name: definition.formula for definition in spec.definitions}

    @cache
    def inline(node: ast.Node) -> ast.Node:
        if isinstance(node, ast.Ref):
            return inline(definitions[node.name])
        return _rebuild(node, tuple(inline(child) for child in node.children()))

    return inline(spec.formula)


# --- Helper functions -----------------------------------------------------------------------


def _read(path: Path, shown: str) -> str:
    try:
        return read_text(path, "specification file")
    except UnreadableFile as error:
        raise SpecError(str(error), shown) from None


MAX_DEPTH = 200  # operator nesting, through defined names; deeper formulas are refused


def _parse(text: str, source: str, base_dir: Path, including: tuple[Path, ...]) -> ast.Spec:
    try:
        spec = _parse_checked(text, source, base_dir, including)
    except RecursionError:
        spec = None
    if spec is None or nesting_depth(spec) > MAX_DEPTH:
        raise StlSyntaxError(f"the specification nests more than {MAX_DEPTH} levels deep (counting through its definitions); simplify it", source)
    return spec


def nesting_depth(spec: ast.Spec) -> int:
    """How deeply the specification's formula nests operators once its names are inlined,
    counted without recursion (names must not be recursive: see `_check_names`)."""
    definitions = {definition.name: definition.formula for definition in spec.definitions}

    def below(node: ast.Node) -> tuple[ast.Node, ...]:
        return (definitions[node.name],) if isinstance(node, ast.Ref) else node.children()

    def depth(node: ast.Node, depths: list[int]) -> int:
        return (0 if isinstance(node, ast.Ref) else 1) + max(depths, default=0)

    return fold(spec.formula, below, depth)


def _parse_checked(text: str, source: str, base_dir: Path, including: tuple[Path, ...]) -> ast.Spec:
    try:
        tree = _parser().parse(text)
        includes, definitions, formula = _ToAst(source).transform(tree)
    except UnexpectedInput as error:
        raise _syntax_error(error, text, source) from None
    except VisitError as error:
        if isinstance(error.orig_exc, SpecError):
            raise error.orig_exc.located(source, text) from None
        raise
    included: list[ast.Definition] = []
    for include_path, line in includes:
        included.extend(_include(include_path, line, text, source, base_dir, including))
    all_definitions = tuple(included + definitions)
    if formula is None:
        if not definitions:
            raise StlSyntaxError("the specification is empty: it needs at least one formula", source)
        formula, name = definitions[-1].formula, definitions[-1].name
    else:
        name = None
    spec = ast.Spec(all_definitions, formula, name)
    try:
        _check_names(spec)
    except SpecError as error:
        raise error.located(error.source, text if error.source == source else None) from None
    return spec


def _include(include_path: str, line: int, text: str, source: str, base_dir: Path, including: tuple[Path, ...]) -> tuple[ast.Definition, ...]:
    path = (base_dir / include_path).resolve()
    if path in including:
        raise StlNameError(f"circular include of '{include_path}'", source, line, 1).located(source, text)
    if not path.is_file():
        problem = "is a folder, not a specification file" if path.is_dir() else "does not exist"
        raise StlNameError(f"included file '{include_path}' {problem}", source, line, 1).located(source, text)
    shown = str(Path(source).parent / include_path) if source != "<string>" else include_path
    spec = _parse(_read(path, shown), shown, path.parent, including + (path,))
    return spec.definitions


def _syntax_error(error: UnexpectedInput, text: str, source: str) -> StlSyntaxError:
    if isinstance(error, UnexpectedEOF):
        lines = text.splitlines() or [""]
        line, column = len(lines), len(lines[-1]) + 1
        message = "unexpected end of input: the formula is incomplete"
    elif isinstance(error, UnexpectedCharacters):
        line, column = error.line, error.column
        message = f"unexpected character {text[error.pos_in_stream]!r}"
    else:
        assert isinstance(error, UnexpectedToken)
        line, column = error.line, error.column
        found = "end of input" if error.token.type == "$END" else repr(str(error.token))
        expected = sorted({_readable(name) for name in error.expected}, key=lambda name: (len(name), name))
        shown = ", ".join(expected[:6]) + (", ..." if len(expected) > 6 else "")
        message = f"unexpected {found}; expected {shown}"
        if error.token.type == "$END":
            lines = text.splitlines() or [""]
            line, column = len(lines), len(lines[-1]) + 1
    return StlSyntaxError(message, source, line, column, caret_context(text, line, column))


def _readable(terminal: str) -> str:
    if terminal in _READABLE_TERMINALS:
        return _READABLE_TERMINALS[terminal]
    pattern = _parser().get_terminal(terminal).pattern
    return repr(pattern.value) if pattern.type == "str" else terminal.lower()


def _rebuild(node: ast.Node, children: tuple[ast.Node, ...]) -> ast.Node:
    """`node` with its children replaced (same order as `node.children()`)."""
    match node:
        case ast.And() | ast.Or():
            return type(node)(children)
        case ast.Not() | ast.Always() | ast.Eventually() | ast.Minus() | ast.Abs() | ast.InRange():
            field_names = [name for name in node.__dataclass_fields__]
            return type(node)(children[0], *[getattr(node, name) for name in field_names[1:]])
        case ast.Implies():
            return ast.Implies(*children)
        case ast.Until():
            return ast.Until(children[0], children[1], node.interval)
        case ast.Compare():
            return ast.Compare(children[0], node.op, children[1])
        case ast.Arith():
            return ast.Arith(node.op, children[0], children[1])
        case _:
            return node


def _check_names(spec: ast.Spec) -> None:
    """Duplicate, undefined and recursive names; formula names used as signals."""
    definitions: dict[str, ast.Definition] = {}
    for definition in spec.definitions:
        if definition.name in definitions:
            raise StlNameError(
                f"'{definition.name}' is defined twice (first at line {definitions[definition.name].line})",
                definition.source,
                definition.line,
                1,
            )
        definitions[definition.name] = definition
    bodies = [definition.formula for definition in spec.definitions] + [spec.formula]
    for node in (node for body in bodies for node in body.walk()):
        if isinstance(node, ast.Ref) and node.name not in definitions:
            raise StlNameError(
                f"undefined formula '{node.name}' (a signal needs a comparison, e.g. {node.name} > 0)",
                node.source,
                node.line,
                node.column,
            )
        if isinstance(node, ast.Signal) and node.name in definitions:
            raise StlNameError(
                f"'{node.name}' is a formula, not a signal: it cannot be used in arithmetic",
                node.source,
                node.line,
                node.column,
            )
    _check_recursion(definitions)


def _check_recursion(definitions: dict[str, ast.Definition]) -> None:
    finished: set[str] = set()

    def visit(name: str, path: tuple[str, ...]) -> None:
        if name in path:
            cycle = path[path.index(name) :] + (name,)
            definition = definitions[cycle[0]]
            raise StlNameError(f"recursive definition: {' -> '.join(cycle)}", definition.source, definition.line, 1)
        if name in finished:
            return
        for node in definitions[name].formula.walk():
            if isinstance(node, ast.Ref):
                visit(node.name, path + (name,))
        finished.add(name)

    for name in definitions:
        visit(name, ())


class _Name:
    """A bare identifier: a signal in arithmetic, a formula reference in logic."""

    def __init__(self, name: str, line: int, column: int, source: str) -> None:
        self.name, self.line, self.column, self.source = name, line, column, source


@v_args(inline=True, meta=True)
class _ToAst(Transformer):
    """Lark tree -> (includes, definitions, final formula or None); checks operand kinds."""

    def __init__(self, source: str) -> None:
        super().__init__()
        self.source = source

    def start(self, meta, *items):
        includes = [item for item in items if isinstance(item, tuple)]
        definitions = [item for item in items if isinstance(item, ast.Definition)]
        formulas = [item for item in items if not isinstance(item, (tuple, ast.Definition))]
        formula = self._formula(formulas[0], meta) if formulas else None
        return includes, definitions, formula

    def include(self, meta, path: Token):
        return python_ast.literal_eval(str(path)), meta.line

    def definition(self, meta, name: Token, body):
        return ast.Definition(str(name), self._formula(body, meta), meta.line, self.source)

    def implies(self, meta, left, right):
        return ast.Implies(self._formula(left, meta), self._formula(right, meta))

    def disjunction(self, meta, *operands):
        return ast.Or(tuple(self._formula(operand, meta) for operand in operands))

    def conjunction(self, meta, *operands):
        return ast.And(tuple(self._formula(operand, meta) for operand in operands))

    def until(self, meta, left, *rest):
        interval, right = (rest[0], rest[1]) if len(rest) == 2 else (None, rest[0])
        return ast.Until(self._formula(left, meta), self._formula(right, meta), interval)

    def negation(self, meta, child):
        return ast.Not(self._formula(child, meta))

    def always(self, meta, *args):
        return ast.Always(self._formula(args[-1], meta), args[0] if len(args) == 2 else None)

    def eventually(self, meta, *args):
        return ast.Eventually(self._formula(args[-1], meta), args[0] if len(args) == 2 else None)

    def compare(self, meta, left, comparator: Token, right):
        return ast.Compare(self._expr(left, meta), ast.Comparator(str(comparator)), self._expr(right, meta))

    def region(self, meta, expr, lo, hi):
        if lo[0] > hi[0]:
            raise StlSyntaxError(f"empty range [{lo[0]:g}, {hi[0]:g}]: the lower end is above the upper", self.source, lo[1], lo[2])
        return ast.InRange(self._expr(expr, meta), lo[0], hi[0])

    def arith(self, meta, left, op: Token, right):
        return ast.Arith(ast.ArithOp(str(op)), self._expr(left, meta), self._expr(right, meta))

    def minus(self, meta, _sign, operand):
        operand = self._expr(operand, meta)
        return ast.Const(-operand.value) if isinstance(operand, ast.Const) else ast.Minus(operand)

    def absolute(self, meta, operand):
        return ast.Abs(self._expr(operand, meta))

    def number(self, meta, token: Token):
        return ast.Const(self._finite(token))

    def name(self, meta, token: Token):
        return _Name(str(token), token.line, token.column, self.source)

    def interval(self, meta, lo, hi):
        for value, line, column in (lo, hi):
            if value < 0:
                raise StlSyntaxError(f"interval bounds must be non-negative (got {value:g})", self.source, line, column)
        if lo[0] > hi[0]:
            raise StlSyntaxError(f"empty interval [{lo[0]:g}, {hi[0]:g}]: the lower bound is above the upper", self.source, lo[1], lo[2])
        return ast.Interval(lo[0], hi[0])

    def bound(self, meta, *tokens: Token):
        value = self._finite(tokens[-1]) * (-1.0 if str(tokens[0]) == "-" else 1.0)
        return value, meta.line, meta.column

    def _finite(self, token: Token) -> float:
        value = float(token)
        if not math.isfinite(value):
            raise StlSyntaxError(f"the number {token} is too large (at most about 1.8e308)", self.source, token.line, token.column)
        return value

    def _formula(self, node, meta) -> ast.Formula:
        if isinstance(node, _Name):
            return ast.Ref(node.name, node.line, node.column, node.source)
        if isinstance(node, ast.Formula):
            return node
        raise StlSyntaxError(
            "expected a formula but found an arithmetic expression (missing a comparison such as > 0?)",
            self.source,
            meta.line,
            meta.column,
        )

    def _expr(self, node, meta) -> ast.Expr:
        if isinstance(node, _Name):
            return ast.Signal(node.name, node.line, node.column, node.source)
        if isinstance(node, ast.Expr):
            return node
        raise StlSyntaxError("expected an arithmetic expression but found a formula", self.source, meta.line, meta.column)
