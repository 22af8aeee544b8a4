"""Parser: every operator, precedence, n-ary chains, definitions, includes and error messages."""

from pathlib import Path

import pytest

from stl_lfd.errors import StlNameError, StlSyntaxError
from stl_lfd.stl import ast, format_spec, load_spec, parse, resolve
from tests.conftest import ROOT

a, b, c = (ast.Compare(ast.Signal(name), ast.Comparator.GT, ast.Const(0.0)) for name in "abc")


def formula(text: str) -> ast.Formula:
    return parse(text).formula


@pytest.mark.parametrize("path", sorted((ROOT / "specs").glob("*.stl")), ids=lambda p: p.name)
def test_every_bundled_spec_parses_and_round_trips(path):
    spec = load_spec(path)
    assert parse(format_spec(spec)) == spec
    assert resolve(spec)


@pytest.mark.parametrize(
    "symbolic, worded",
    [
        ("!a > 0", "not a > 0"),
        ("a > 0 & b > 0", "a > 0 and b > 0"),
        ("a > 0 | b > 0", "a > 0 or b > 0"),
        ("a > 0 -> b > 0", "a > 0 implies b > 0"),
        ("G[1, 2] a > 0", "always[1, 2] a > 0"),
        ("F a > 0", "eventually a > 0"),
        ("a > 0 U[0, 3] b > 0", "a > 0 until[0, 3] b > 0"),
    ],
)
def test_keywords_and_symbols_mean_the_same(symbolic, worded):
    assert formula(symbolic) == formula(worded)


@pytest.mark.parametrize(
    "text, expected",
    [
        ("!a > 0", ast.Not(a)),
        ("a > 0 & b > 0 & c > 0", ast.And((a, b, c))),
        ("(a > 0 & b > 0) & c > 0", ast.And((ast.And((a, b)), c))),
        ("a > 0 & (b > 0 & c > 0)", ast.And((a, ast.And((b, c))))),
        ("a > 0 | b > 0 & c > 0", ast.Or((a, ast.And((b, c))))),
        ("a > 0 -> b > 0 | c > 0", ast.Implies(a, ast.Or((b, c)))),
        ("a > 0 -> b > 0 -> c > 0", ast.Implies(a, ast.Implies(b, c))),
        ("a > 0 U b > 0 & c > 0", ast.And((ast.Until(a, b), c))),
        ("G a > 0 U b > 0", ast.Until(ast.Always(a), b)),
        ("!a > 0 & b > 0", ast.And((ast.Not(a), b))),
        ("F[2, 4.5] a > 0", ast.Eventually(a, ast.Interval(2, 4.5))),
        ("G G[0,1] a > 0", ast.Always(ast.Always(a, ast.Interval(0, 1)))),
        ("a > 0 U[1, 2] b > 0", ast.Until(a, b, ast.Interval(1, 2))),
    ],
)
def test_operators_and_precedence(text, expected):
    assert formula(text) == expected


def test_arithmetic_precedence():
    x, y, z = (ast.Signal(name) for name in "xyz")
    parsed = formula("x + 2 * y > -abs(z - 1) / 4")
    right = ast.Arith(ast.ArithOp.DIV, ast.Minus(ast.Abs(ast.Arith(ast.ArithOp.SUB, z, ast.Const(1)))), ast.Const(4))
    assert parsed == ast.Compare(ast.Arith(ast.ArithOp.ADD, x, ast.Arith(ast.ArithOp.MUL, ast.Const(2), y)), ast.Comparator.GT, right)
    assert formula("x - y - z < 1e-3").left == ast.Arith(ast.ArithOp.SUB, ast.Arith(ast.ArithOp.SUB, x, y), z)


def test_region_sugar_comments_and_definitions():
    spec = parse("# regions\nL1 := x in [-0.35, -0.25] & y in [0.15, 0.25]  # a box\nphi := F L1\n")
    assert spec.name == "phi"
    assert spec.definition("L1") == ast.And((ast.InRange(ast.Signal("x"), -0.35, -0.25), ast.InRange(ast.Signal("y"), 0.15, 0.25)))
    assert resolve(spec) == ast.Eventually(spec.definition("L1"))


def test_bare_formula_on_the_last_line():
    spec = parse("A := x > 0\nF A & G x < 2\n")
    assert spec.name is None
    assert resolve(spec) == ast.And((ast.Eventually(formula("x > 0")), ast.Always(formula("x < 2"))))


def test_include_brings_definitions(tmp_path: Path):
    (tmp_path / "regions.stl").write_text("R := x in [0, 1]\n")
    (tmp_path / "spec.stl").write_text('include "regions.stl"\nphi := F R\n')
    assert resolve(load_spec(tmp_path / "spec.stl")) == ast.Eventually(ast.InRange(ast.Signal("x"), 0, 1))


@pytest.mark.parametrize(
    "text, error, message, line, column",
    [
        ("phi := F[1, 2 x > 0", StlSyntaxError, "unexpected 'x'; expected", 1, 15),
        ("phi := x > 1 $", StlSyntaxError, "unexpected character '$'", 1, 14),
        ("phi := F x >\n", StlSyntaxError, "unexpected end of input", 1, 13),
        ("phi := F[5, 2] x > 0", StlSyntaxError, "empty interval [5, 2]", 1, 10),
        ("phi := F[-1, 2] x > 0", StlSyntaxError, "must be non-negative (got -1)", 1, 10),
        ("phi := x in [3, 1]", StlSyntaxError, "empty range [3, 1]", 1, 14),
        ("phi := x + 3", StlSyntaxError, "expected a formula but found an arithmetic expression", 1, 1),
        ("A := x > 0\nphi := F B", StlNameError, "undefined formula 'B'", 2, 10),
        ("A := x > 0\nphi := A + 1 > 0", StlNameError, "'A' is a formula, not a signal", 2, 8),
        ("A := B\nB := F A\n", StlNameError, "recursive definition: A -> B -> A", 1, 1),
        ("A := x > 0\nA := x > 1\n", StlNameError, "'A' is defined twice", 2, 1),
        ("# nothing\n", StlSyntaxError, "the specification is empty", 0, 0),
    ],
)
def test_errors_name_line_and_column(text, error, message, line, column):
    with pytest.raises(error) as caught:
        parse(text, "spec.stl")
    assert message in caught.value.message
    assert (caught.value.line, caught.value.column) == (line, column)
    if line:
        rendered = str(caught.value).splitlines()
        assert rendered[0].startswith(f"spec.stl:{line}:{column}: ")
        assert rendered[2].index("^") == rendered[1].index(text.splitlines()[line - 1][:1]) + column - 1


def test_include_errors(tmp_path: Path):
    (tmp_path / "loop.stl").write_text('include "loop.stl"\nphi := x > 0\n')
    with pytest.raises(StlNameError, match="circular include"):
        load_spec(tmp_path / "loop.stl")
    (tmp_path / "missing.stl").write_text('include "nowhere.stl"\nphi := x > 0\n')
    with pytest.raises(StlNameError, match="'nowhere.stl' does not exist"):
        load_spec(tmp_path / "missing.stl")
    (tmp_path / "broken.stl").write_text("R := x in [0,\n")
    (tmp_path / "user.stl").write_text('include "broken.stl"\nphi := F R\n')
    with pytest.raises(StlSyntaxError, match="broken.stl:1:14: unexpected end of input"):
        load_spec(tmp_path / "user.stl")
