"""Property-based tests of the compiled robustness against the plain evaluators of definitions.py."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stl_lfd.stl import compile_spec, definitions, format_formula, parse
from tests.stl.strategies import formulas, traces

pytestmark = pytest.mark.filterwarnings("ignore::stl_lfd.stl.robustness.HorizonWarning")


def close(a: float, b: float, tolerance: float = 1e-9) -> bool:
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= tolerance * max(1.0, abs(a), abs(b))


@pytest.mark.slow
@given(formulas, traces())
def test_classic_equals_reference_at_every_sample(formula, trace):
    signals, times = trace
    compiled = compile_spec(formula, "classic").trace(signals, times)
    expected = [definitions.classic(formula, signals, times, k) for k in range(times.size)]
    assert all(close(a, b) for a, b in zip(compiled, expected)), (format_formula(formula), compiled, expected)


@given(formulas, traces(), st.sampled_from([0.5, 1.0, 3.0]))
def test_new_equals_reference_at_first_sample(formula, trace, nu):
    signals, times = trace
    compiled = compile_spec(formula, "new", nu)(signals, times)
    expected = definitions.new(formula, signals, times, 0, nu)
    assert close(compiled, expected, 1e-7), (format_formula(formula), compiled, expected)


@given(formulas, traces(), st.sampled_from(["classic", "new"]))
def test_sign_agrees_with_boolean_semantics(formula, trace, semantics):
    signals, times = trace
    values = compile_spec(formula, semantics).trace(signals, times)
    assert not np.any(np.isnan(values))
    for k, value in enumerate(values):
        if value != 0:
            assert (value > 0) == definitions.boolean(formula, signals, times, k), (format_formula(formula), k, value)


@given(formulas, traces())
def test_new_tends_to_classic_as_nu_grows(formula, trace):
    signals, times = trace
    classic = compile_spec(formula, "classic")(signals, times)
    errors = [abs(compile_spec(formula, "new", nu)(signals, times) - classic) for nu in (1e2, 1e4, 1e6)]
    if math.isinf(classic):
        assert all(math.isnan(error) for error in errors)  # inf - inf: both infinite and equal
        return
    assert errors[-1] <= 1e-4 * max(1.0, abs(classic)), (format_formula(formula), classic, errors)
    assert errors[-1] <= errors[0] + 1e-12


@given(formulas, traces(batch=3), st.sampled_from(["classic", "new"]))
def test_batch_equals_each_trace(formula, trace, semantics):
    signals, times = trace
    function = compile_spec(formula, semantics)
    batch = function(signals, times)
    assert batch.shape == (3,)
    for index in range(3):
        single = function({name: values[index] for name, values in signals.items()}, times)
        assert close(batch[index], single, 1e-12)


@pytest.mark.slow
@given(formulas)
@settings(max_examples=300)
def test_printed_formula_parses_to_the_same_tree(formula):
    assert parse(format_formula(formula)).formula == formula
