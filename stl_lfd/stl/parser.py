"""Parse STL specification text into the typed syntax tree of `stl_lfd.stl.ast`.

Entry points: `parse(text, source)` for text, `load_spec(path)` for files (which also follows
`include` lines), and `resolve(spec)` to inline defined names into one formula.

Specifications of any size parse in time linear in their length: Lark's LALR parser calls the
transformer as it reduces each rule (no parse tree is built), and parsing, checking, inlining,
printing and compiling walk the tree with their own stacks. Nesting is limited to `MAX_DEPTH`
levels, counted through defined names, which keeps what does recurse (evaluating, at most two
stack frames a level; Python's own comparison, repr and pickling of trees, about four) well
within Python's recursion limit of 1000. The parser notes the first operator past the limit;
the names are then followed, and a deeper specification is refused with one line naming the
file, line and column.
"""

from __future__ import annotations

import threading
from functools import cache
from pathlib import Path

from lark import Lark
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from stl_lfd.errors import SpecError, StlNameError, StlSyntaxError, caret_context
from stl_lfd.files import UnreadableFile, read_text
from stl_lfd.stl import ast
from stl_lfd.stl.transformer import MAX_DEPTH, ToAst

_TOO_DEEP = f"the specification nests more than {MAX_DEPTH} levels deep (counting through its definitions); simplify it"

_SHOWN_COLUMNS = 120  # of a source line shown under an error
MAX_SPEC_BYTES = 1_000_000  # a generated specification may be large; a megabyte is a wrong file

_READABLE_TERMINALS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "COMPARATOR": "a comparison (< <= > >=)",
    "ESCAPED_STRING": "a quoted file name",
    "$END": "end of input",
}


@cache
def _parser() -> tuple[Lark, "ToAst"]:
    transformer = ToAst()
    lark = Lark.open("stl.lark", rel_to=__file__, parser="lalr", transformer=transformer, keep_all_tokens=True, cache=True)
    return lark, transformer


_PARSING = threading.Lock()  # the transformer names the source of the text being parsed


def parse(text: str, source: str = "<string>", base_dir: Path | None = None) -> ast.Spec:
    """Parse a specification.

    Args:
        text: the specification text.
        source: name used in error messages (usually the file path).
        base_dir: folder that `include` paths are relative to (default: the current folder).

    Returns:
        The `Spec`, with definitions checked: no duplicates, no undefined or recursive names,
        nesting within `MAX_DEPTH`.

    Raises:
        StlSyntaxError, StlNameError: with line, column and a caret under the offending text.
    """
    return _parse(text, source, base_dir or Path.cwd(), including=())


def load_spec(path: str | Path) -> ast.Spec:
    """Read and parse a specification file (see `parse`)."""
    path = Path(path)
    return _parse(_read(path, str(path)), str(path), path.parent, including=())


def resolve(spec: ast.Spec, formula: ast.Formula | None = None) -> ast.Formula:
    """The specification formula (or `formula`, a part of it) with every defined name
    replaced by its definition.

    A definition used several times becomes one shared subtree (the result is a directed
    acyclic graph), so inlining takes time linear in the specification's size.
    """
    formula = spec.formula if formula is None else formula

    def below(node: ast.Node) -> tuple[ast.Node, ...]:  # names are never inside a predicate
        if isinstance(node, ast.Ref):
            return (spec.definition(node.name),)
        return () if isinstance(node, (ast.Compare, ast.InRange)) else node.children()

    inlined: dict[int, ast.Node] = {}
    with ast.collector_paused():
        for node in ast.post_order(formula, below):
            children = below(node)
            if isinstance(node, ast.Ref):
                inlined[id(node)] = inlined[id(children[0])]
            elif not children:
                inlined[id(node)] = node
            else:
                new = [inlined[id(child)] for child in children]
                changed = any(new_child is not child for new_child, child in zip(new, children))
                inlined[id(node)] = _rebuild(node, tuple(new)) if changed else node
    return inlined[id(formula)]  # type: ignore[return-value]


def nesting_depth(spec: ast.Spec) -> int:
    """How deeply the specification's formula nests operators once its names are inlined
    (a predicate `x > 0` is 2 levels). Names must not be recursive (see `_check_names`)."""
    return _depths(spec)[id(spec.formula)]


# --- Helper functions -----------------------------------------------------------------------


def _read(path: Path, shown: str) -> str:
    try:
        return read_text(path, "specification file", MAX_SPEC_BYTES)
    except UnreadableFile as error:
        raise SpecError(str(error), shown) from None


def _parse(text: str, source: str, base_dir: Path, including: tuple[Path, ...]) -> ast.Spec:
    includes, definitions, formula, too_deep, uses_names = _parse_text(text, source)
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
        raise _placed(error, error.source, text if error.source == source else None) from None
    if too_deep is not None:  # one line, without the source line (it may be megabytes long)
        raise StlSyntaxError(_TOO_DEEP, source, *too_deep)
    if uses_names:  # else the parser has checked the depth
        _check_depth(spec)
    return spec


def _parse_text(text: str, source: str):
    """(includes as (path, line), definitions, final formula or None, (line, column) past the
    nesting limit or None, whether a formula uses a defined name) of one text."""
    lark, transformer = _parser()
    try:
        with _PARSING, ast.collector_paused():
            transformer.reset(source)
            includes, definitions, formula = lark.parse(text)
            error, too_deep, uses_names = transformer.error, transformer.too_deep, transformer.uses_names
    except UnexpectedInput as syntax:
        raise _syntax_error(syntax, text, source) from None
    if error is not None:
        raise _placed(error, source, text)
    return includes, definitions, formula, too_deep, uses_names


def _depths(spec: ast.Spec) -> dict[int, int]:
    """id(node) -> nesting depth, for the nodes of the specification's formula and of the
    definitions it uses (a name is as deep as its definition)."""

    def below(node: ast.Node) -> tuple[ast.Node, ...]:
        return (spec.definition(node.name),) if isinstance(node, ast.Ref) else node.children()

    depths: dict[int, int] = {}
    for node in ast.post_order(spec.formula, below):
        depths[id(node)] = ast.depth(node, [depths[id(child)] for child in below(node)])
    return depths


def _check_depth(spec: ast.Spec) -> None:
    """Refuse a formula nesting more than `MAX_DEPTH` levels through its definitions, at the
    first use of a name that takes it past the limit (each text alone is within the limit,
    which the parser checks as it goes)."""
    depths = _depths(spec)
    if depths[id(spec.formula)] <= MAX_DEPTH:
        return
    stack: list[tuple[ast.Node, int]] = [(spec.formula, 0)]  # (node, levels above it)
    while stack:
        node, above = stack.pop()
        if isinstance(node, ast.Ref) and above + depths[id(node)] > MAX_DEPTH:
            raise StlSyntaxError(_TOO_DEEP, node.source, node.line, node.column)
        stack.extend((child, above + 1) for child in reversed(node.children()))
    raise AssertionError("a formula too deep through its definitions has a name that makes it so")


def _include(include_path: str, line: int, text: str, source: str, base_dir: Path, including: tuple[Path, ...]) -> tuple[ast.Definition, ...]:
    path = (base_dir / include_path).resolve()
    if path in including:
        raise _placed(StlNameError(f"circular include of '{include_path}'", source, line, 1), source, text)
    if not path.is_file():
        problem = "is a folder, not a specification file" if path.is_dir() else "does not exist"
        raise _placed(StlNameError(f"included file '{include_path}' {problem}", source, line, 1), source, text)
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
    return StlSyntaxError(message, source, line, column, _context(text, line, column))


def _placed(error: SpecError, source: str, text: str | None) -> SpecError:
    """`error` naming `source` and showing the offending line of `text` (default: the file)."""
    if text is None and not error.context and error.line:
        text = source_text(source)
    context = _context(text, error.line, error.column) if text is not None else error.context
    return type(error)(error.message, source, error.line, error.column, context)


def source_text(source: str) -> str | None:
    """The text of the specification file `source`, None when it cannot be read."""
    try:
        return read_text(source, "specification file", MAX_SPEC_BYTES)
    except UnreadableFile:
        return None


def _context(text: str, line: int, column: int) -> str:
    """The line and a caret under the column, cut to `_SHOWN_COLUMNS` around the column when
    longer (a generated specification may be megabytes on one line)."""
    lines = text.splitlines()
    if not 1 <= line <= len(lines) or len(lines[line - 1]) <= _SHOWN_COLUMNS:
        return caret_context(text, line, column)
    source_line = lines[line - 1]
    start = max(0, min(column - 1 - _SHOWN_COLUMNS // 2, len(source_line) - _SHOWN_COLUMNS))
    stop = start + _SHOWN_COLUMNS
    shown = ("..." if start else "") + source_line[start:stop] + ("..." if stop < len(source_line) else "")
    return caret_context(shown, 1, column - start + (3 if start else 0))


def _readable(terminal: str) -> str:
    if terminal in _READABLE_TERMINALS:
        return _READABLE_TERMINALS[terminal]
    pattern = _parser()[0].get_terminal(terminal).pattern
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
    """Duplicate, undefined and recursive names; formula names used as signals (the first in
    the order of the text: names and signals are leaves, which `ast.post_order` gives in that
    order)."""
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
    bodies = [definition.formula for definition in spec.definitions]
    if spec.name is None:  # a bare formula; else it is the last definition's
        bodies.append(spec.formula)
    for node in (node for body in bodies for node in ast.post_order(body)):
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
    """A depth-first search of the names each definition uses, with its own stack (a chain of
    many definitions must not exhaust Python's)."""
    finished: set[str] = set()
    for root in definitions:
        if root in finished:
            continue
        path, on_path = [root], {root}
        pending = [_names_used(definitions[root])]
        while pending:
            name = next(pending[-1], None)
            if name is None:
                pending.pop()
                on_path.discard(path[-1])
                finished.add(path.pop())
            elif name in on_path:
                cycle = path[path.index(name) :] + [name]
                definition = definitions[cycle[0]]
                raise StlNameError(f"recursive definition: {' -> '.join(cycle)}", definition.source, definition.line, 1)
            elif name not in finished:
                path.append(name)
                on_path.add(name)
                pending.append(_names_used(definitions[name]))


def _names_used(definition: ast.Definition):
    return (node.name for node in ast.post_order(definition.formula) if isinstance(node, ast.Ref))
