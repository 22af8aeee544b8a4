"""Specifications of any size: nesting past the limit is one error line; at the limit, and for
large flat conjunctions and many definitions, every step works and gives the right value.

Speed is measured in benchmarks/bench_stl.py; these tests assert values only.
"""

from __future__ import annotations

import copy
import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.errors import SpecError, StlSyntaxError
from stl_lfd.signals import read_signal_csv
from stl_lfd.stl import ast, compile_spec, format_formula, format_spec, parse, resolve, split_spec
from stl_lfd.stl.kernels import new_conjunction
from stl_lfd.stl.parser import MAX_DEPTH, nesting_depth
from tests.conftest import ROOT
from tests.stl.strategies import formulas, traces

S1 = ROOT / "examples" / "s1.csv"
runner = CliRunner()


def first_value() -> float:
    """The signal `s` of examples/s1.csv at its first sample."""
    return float(read_signal_csv(S1).columns["s"][0])


def robustness_command(tmp_path: Path, text: str, *options: str):
    """`stlopt robustness` of `text` on S1; the classic robustness (the value these tests work
    out by hand) unless `options` name the semantics."""
    path = tmp_path / "spec.stl"
    path.write_text(text)
    semantics = () if "--semantics" in options else ("--semantics", "classic")
    return path, runner.invoke(app, ["robustness", str(path), str(S1), *options, *semantics])


# --- nesting past the limit --------------------------------------------------------------------

TOO_DEEP = {
    "G nested 3,000 times": ("G[0,1] " * 3000 + "s > 0\n", (1, 7 * (3000 - MAX_DEPTH + 1) + 1)),
    "5,000 chained ->": (" -> ".join(f"s > {i}" for i in range(5000)) + "\n", None),
    "5,000 negations": ("phi := " + "!" * 5000 + "s > 0\n", (1, 8 + 5000 - MAX_DEPTH + 1)),
    "500 nested parentheses": ("(s > 0 & " * 500 + "s > 1" + ")" * 500 + "\n", None),
    "a sum of 5,000 terms": (" + ".join(["s"] * 5000) + " > 0\n", None),
    "3,000 nested abs": ("abs(" * 3000 + "s" + ")" * 3000 + " > 0\n", None),
    "5,000 chained U": (" U ".join(f"s > {i}" for i in range(5000)) + "\n", None),
    "1,000 definitions in a chain": ("A0 := s > 0\n" + "".join(f"A{i} := F A{i - 1}\n" for i in range(1, 1000)), (1000, 11)),
}


@pytest.mark.parametrize("text, place", TOO_DEEP.values(), ids=TOO_DEEP.keys())
def test_too_deep_is_one_error_line_naming_the_place(tmp_path, text, place):
    path, result = robustness_command(tmp_path, text)
    assert result.exit_code == 3, result.stderr
    assert "Traceback" not in result.stderr + result.stdout and result.stdout == ""
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"error: {path}:")
    assert f"nests more than {MAX_DEPTH} levels deep" in line
    if place is not None:
        assert line.startswith(f"error: {path}:{place[0]}:{place[1]}: ")


def test_the_nesting_limit_counts_through_definitions_at_the_name_that_passes_it():
    text = "A0 := s > 0\n" + "".join(f"A{i} := F A{i - 1}\n" for i in range(1, 199)) + "phi := G[0, 1] A198 & F A198\n"
    with pytest.raises(StlSyntaxError, match="nests more than 200") as caught:
        parse(text, "spec.stl")
    assert (caught.value.line, caught.value.column) == (200, 16)
    assert nesting_depth(parse(text.replace("G[0, 1] A198 & F A198", "A197 & F A196"))) == MAX_DEPTH


def test_an_unused_definition_too_deep_is_refused_too():
    with pytest.raises(StlSyntaxError, match="nests more than 200") as caught:
        parse("deep := " + "!" * 300 + "s > 0\nphi := s > 0\n")
    assert caught.value.line == 1


def test_a_syntax_error_after_a_too_deep_formula_is_the_one_reported():
    with pytest.raises(StlSyntaxError, match="unexpected"):
        parse("!" * 300 + "s > 0 )")


def test_a_formula_built_too_deep_in_code_is_refused_before_evaluation():
    formula: ast.Formula = ast.Compare(ast.Signal("s"), ast.Comparator.GT, ast.Const(0.0))
    for _ in range(5000):
        formula = ast.Not(formula)
    with pytest.raises(SpecError, match="nests more than 200"):
        compile_spec(formula)


# --- nesting at the limit ----------------------------------------------------------------------

AT_LIMIT = {
    "G": ("G[0, 0.1] " * 198 + "s > 0", 0.25),
    "not": ("!" * 198 + "s > 0", 0.25),
    "implies": " -> ".join(["s > 1"] * 198 + ["s > 0"]),
    "until": " U[0, 0.1] ".join(["s > 0"] * 199),
    "and": "(s > 1 | " * 99 + "(s > 0 & " * 99 + "s > 0" + ")" * 198,
    "sum": " + ".join(["s"] * 199) + " > 0",
    "minus": ("-" * 198 + "s > 0", 0.25),
    "abs": ("abs(" * 198 + "s" + ")" * 198 + " > 0", 0.25),
    "definitions": "A0 := s > 0\n" + "".join(f"A{i} := (A{i - 1} & A{i - 1})\n" for i in range(1, 199)),
}


def stack_depth() -> int:
    frame, depth = sys._getframe(), 0
    while frame is not None:
        frame, depth = frame.f_back, depth + 1
    return depth


@pytest.mark.parametrize("case", AT_LIMIT.values(), ids=AT_LIMIT.keys())
def test_every_step_works_at_the_limit_with_two_stack_frames_per_level(case):
    """Parsing, printing, inlining, compiling, evaluating and splitting take at most two stack
    frames per level (Python's own comparison, repr and pickle of a tree take about four)."""
    text, expected = case if isinstance(case, tuple) else (case, None)
    table = read_signal_csv(S1)
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(stack_depth() + 2 * MAX_DEPTH + 60)
    try:
        spec = parse(text)
        printed = format_spec(spec)
        resolve(spec)
        for semantics in ("classic", "new"):
            function = compile_spec(spec, semantics)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                value = function(table.columns, table.times)
                assert function.trace(table.columns, table.times).shape == table.times.shape
            assert math.isfinite(value)
            if expected is not None and semantics == "classic":
                assert value == pytest.approx(expected)
        assert split_spec(spec).names
    finally:
        sys.setrecursionlimit(limit)
    assert nesting_depth(spec) == MAX_DEPTH
    assert parse(printed) == spec


# --- large specifications ----------------------------------------------------------------------


def test_a_conjunction_of_50000_predicates_and_a_disjunction_of_20000(tmp_path):
    count = 50_000
    _, result = robustness_command(tmp_path, " & ".join(f"s > {i}" for i in range(count)) + "\n")
    assert result.exit_code == 0, result.stderr
    assert float(result.stdout) == pytest.approx(first_value() - (count - 1))
    count = 20_000
    _, result = robustness_command(tmp_path, " | ".join(f"s < {i}" for i in range(count)) + "\n", "--semantics", "new", "--nu", "2")
    assert result.exit_code == 0, result.stderr
    expected = -new_conjunction(-(np.arange(count) - first_value()), 2.0)
    assert float(result.stdout) == pytest.approx(expected, rel=1e-9)


def test_20000_definitions_each_using_earlier_ones(tmp_path):
    count = 20_000
    offsets = [(i % 97) / 100 for i in range(count)]
    lines = ["d0 := s > 0", "d1 := s > 0.01"] + [f"d{i} := d{i // 2} & s > {offsets[i]}" for i in range(2, count)]
    lines.append("spec := " + " | ".join(f"d{i}" for i in range(count - 100, count)))
    _, result = robustness_command(tmp_path, "\n".join(lines) + "\n")
    assert result.exit_code == 0, result.stderr

    def value(i: int) -> float:  # d_i is the conjunction along i, i // 2, ..., 1
        path = [i]
        while path[-1] > 1:
            path.append(path[-1] // 2)
        return min(first_value() - offsets[j] for j in path)

    assert float(result.stdout) == pytest.approx(max(value(i) for i in range(count - 100, count)))


def test_a_definition_used_twice_at_each_of_99_levels_is_evaluated_once_per_level():
    text = "d0 := s > 0.2\n" + "".join(f"d{i} := (d{i - 1} & F[0, 0.05] d{i - 1})\n" for i in range(1, 100))
    spec = parse(text)
    table = read_signal_csv(S1)
    assert compile_spec(spec, "classic")(table.columns, table.times) == pytest.approx(first_value() - 0.2)
    assert compile_spec(spec, "new")(table.columns, table.times) > 0
    assert len(format_formula(spec.formula)) < 50  # printed with its names, not spelled out


@settings(max_examples=40)
@given(formulas, traces(), st.sampled_from(["classic", "new"]))
def test_a_shared_subformula_gives_the_values_of_its_copies(formula, trace, semantics):
    signals, times = trace
    window = ast.Interval(0, 0.5)

    def around(a, b, c):
        return ast.And((a, ast.Eventually(ast.Or((b, ast.Not(c))), window), ast.Until(b, c, window)))

    shared = around(formula, formula, formula)
    copies = around(formula, copy.deepcopy(formula), copy.deepcopy(formula))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.array_equal(compile_spec(shared, semantics).trace(signals, times), compile_spec(copies, semantics).trace(signals, times))


def test_resolve_shares_a_definition_used_twice():
    formula = resolve(parse("A := x > 0\nphi := A & F A\n"))
    assert formula.operands[0] is formula.operands[1].child


def test_an_error_in_a_long_line_shows_only_the_text_around_it():
    text = " & ".join(f"s > {i}" for i in range(10_000)) + " & s > $"
    with pytest.raises(StlSyntaxError, match="unexpected character") as caught:
        parse(text, "spec.stl")
    shown, caret = str(caught.value).splitlines()[1:]
    assert len(shown) < 140 and shown.endswith("s > $") and shown[caret.index("^")] == "$"
