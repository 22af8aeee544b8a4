"""Hand-computed robustness values for every operator under both semantics."""

import math

import numpy as np
import pytest

from stl_lfd.errors import SignalError, SpecError, StlNameError
from stl_lfd.stl import HorizonWarning, compile_spec, kernels, parse
from stl_lfd.stl.kernels import new_conjunction

TIMES5 = np.arange(5.0)


def robustness(text, signals, times=TIMES5, semantics="classic", nu=1.0):
    return compile_spec(parse(text), semantics, nu)(signals, times)


def constant(**values):
    return {name: np.full(5, float(value)) for name, value in values.items()}


# --- predicates and arithmetic (the same in both semantics) ---------------------------------


@pytest.mark.parametrize("semantics", ["classic", "new"])
@pytest.mark.parametrize(
    "text, expected",
    [
        ("x > 0.3", 0.2),
        ("x >= 0.3", 0.2),
        ("x < 0.3", -0.2),
        ("x <= 0.3", -0.2),
        ("0.3 < x", 0.2),
        ("x in [0.4, 0.6]", 0.1),
        ("x in [0.0, 0.2]", -0.3),
        ("x + y > 1", 0.5),
        ("x - y > 0", -0.5),
        ("x * y > 0", 0.5),
        ("y / x > 1", 1.0),
        ("-x > -1", 0.5),
        ("abs(x - y) < 2", 1.5),
        ("2 * x + y * 3 > 0", 4.0),
    ],
)
def test_predicates(semantics, text, expected):
    assert robustness(text, constant(x=0.5, y=1.0), semantics=semantics) == pytest.approx(expected)


# --- Boolean operators -------------------------------------------------------------------------


def test_classic_boolean_operators():
    signals = constant(a=1, b=2, c=-3)
    assert robustness("!(a > 0)", signals) == -1
    assert robustness("a > 0 & b > 0 & c > 0", signals) == -3
    assert robustness("a > 0 | b > 0 | c > 0", signals) == 2
    assert robustness("a > 0 -> c > 0", signals) == -1
    assert robustness("c > 0 -> a > 0", signals) == 3


def test_new_conjunction_values_from_the_notes():
    signals = constant(a=1, b=2, c=3)
    assert robustness("a > 0 & b > 0 & c > 0", signals, semantics="new") == pytest.approx(1.4247896174, abs=1e-10)
    assert robustness("a > 0 & (b > 0 & c > 0)", signals, semantics="new") == pytest.approx(1.27744, abs=1e-5)
    assert robustness("(a > 0 & b > 0) & c > 0", signals, semantics="new") == pytest.approx(1.62132, abs=1e-5)
    assert robustness("a > 0 & b > 0 & c > 0", signals, semantics="new", nu=10) == pytest.approx(1.00004540199, abs=1e-11)


def test_new_conjunction_negative_branch():
    # rho = (-1, 2): rho_min = -1, relative = (0, -3); -1 (1 + e^-3 e^-3) / (1 + e^-3)
    expected = -(1 + math.exp(-6)) / (1 + math.exp(-3))
    assert robustness("a > 0 & b > 0", constant(a=-1, b=2), semantics="new") == pytest.approx(expected)
    assert robustness("a > 0 & b > 0", constant(a=0, b=2), semantics="new") == 0.0


def test_new_negation_disjunction_and_implication_follow_de_morgan():
    signals = constant(a=1, b=2, c=3)
    conjunction = 1.4247896174
    assert robustness("!(a > 0 & b > 0 & c > 0)", signals, semantics="new") == pytest.approx(-conjunction)
    assert robustness("a < 0 | b < 0 | c < 0", signals, semantics="new") == pytest.approx(-conjunction)
    expected_implies = -new_conjunction(np.array([1.0, -2.0]), 1.0)  # !a | b = !(a & !b)
    assert robustness("a > 0 -> b > 0", signals, semantics="new") == pytest.approx(expected_implies)


# --- temporal operators ------------------------------------------------------------------------

X = {"x": np.array([0.1, -0.2, 0.4, 0.3, -0.5])}


@pytest.mark.parametrize(
    "text, expected",
    [
        ("G x > 0", -0.5),
        ("F x > 0", 0.4),
        ("G[0, 1] x > 0", -0.2),
        ("G[2, 3] x > 0", 0.3),
        ("F[1, 2] x > 0", 0.4),
        ("F[3, 10] x > 0", 0.3),
        ("G[1.5, 2.5] x > 0", 0.4),
        ("F[5, 6] x > 0", -math.inf),
        ("G[5, 6] x > 0", math.inf),
        ("F[0.2, 0.8] x > 0", -math.inf),
    ],
)
def test_classic_temporal(text, expected):
    with pytest.warns(HorizonWarning) if "10" in text or "[5" in text else _no_warning():
        assert robustness(text, X) == pytest.approx(expected)


class _no_warning:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_new_temporal_is_one_nary_conjunction_over_the_window():
    window = np.array([0.4, 0.3])
    assert robustness("G[2, 3] x > 0", X, semantics="new") == pytest.approx(new_conjunction(window, 1.0))
    assert robustness("F[2, 3] x > 0", X, semantics="new") == pytest.approx(-new_conjunction(-window, 1.0))
    assert robustness("G x > 0", X, semantics="new") == pytest.approx(new_conjunction(X["x"], 1.0))


def test_interval_ends_are_inclusive_with_tolerance():
    times = np.round(np.arange(11) * 0.1, 12)  # 0.30000000000000004-style sums do not matter
    signal = {"x": np.where(np.arange(11) == 3, 1.0, -1.0)}
    assert robustness("F[0.3, 0.3] x > 0", signal, times) == 1.0
    assert robustness("F[0, 0.29] x > 0", signal, times) == -1.0


# The 5-sample until case: a = (1, 2, 3, -1, 1), b = (-1, -2, 0.5, 2, 3), one sample per second.
UNTIL = {"a": np.array([1.0, 2, 3, -1, 1]), "b": np.array([-1.0, -2, 0.5, 2, 3])}


def test_classic_until_five_samples():
    # t=0: t'=1: min(b1, a0) = -2; t'=2: min(0.5, 1, 2) = 0.5; t'=3: min(2, 1, 2, 3) = 1 -> 1
    function = compile_spec(parse("a > 0 U[1, 3] b > 0"), "classic")
    assert list(function.trace(UNTIL, TIMES5)) == [1.0, 2.0, 2.0, -1.0, -math.inf]
    # Unbounded until includes t' = t, where a is not required.
    assert robustness("a > 0 U b > 0", UNTIL) == 1.0
    assert robustness("a > 0 U[0, 0] b > 0", UNTIL) == -1.0


def test_new_until_five_samples():
    # t=0: or( and(-2, 1), and(0.5, 1, 2), and(2, 1, 2, 3) ) with the paper's conjunction
    # = or(-1.71660, 0.68244, 1.53793) = 1.21957 (worked by hand with nu = 1).
    assert robustness("a > 0 U[1, 3] b > 0", UNTIL, semantics="new") == pytest.approx(1.21957125, abs=1e-8)


@pytest.mark.parametrize("semantics", ["classic", "new"])
def test_empty_windows_never_give_nan(semantics):
    with pytest.warns(HorizonWarning):
        assert robustness("F[10, 12] x > 0 | x > 0", X, semantics=semantics) == pytest.approx(0.1)
        assert robustness("G[10, 12] x > 0 & x > 0", X, semantics=semantics) == pytest.approx(0.1)
        assert robustness("x > 0 U[10, 12] x > 0", X, semantics=semantics) == -math.inf
        assert robustness("!G[10, 12] x > 0", X, semantics=semantics) == -math.inf


def test_batch_of_traces():
    signals = {"x": np.stack([X["x"], -X["x"]])}
    assert list(compile_spec(parse("F x > 0"), "classic")(signals, TIMES5)) == pytest.approx([0.4, 0.5])


def test_horizon_warning_names_the_lookahead():
    with pytest.warns(HorizonWarning, match="looks 12 s ahead but the trace lasts 4 s"):
        robustness("G[2, 12] x > 0", X)


# --- input errors ------------------------------------------------------------------------------


def test_unknown_signal_names_the_position():
    with pytest.raises(StlNameError, match="unknown signal 'q'") as caught:
        robustness("x > 0 & F q > 1", X)
    assert (caught.value.line, caught.value.column) == (1, 11)


def test_bad_times():
    with pytest.raises(SignalError, match="not uniform"):
        robustness("x > 0", X, np.array([0, 1, 2, 3, 5.0]))
    with pytest.raises(SignalError, match="strictly increasing"):
        robustness("x > 0", X, np.array([0, 1, 1, 3, 4.0]))


def test_bad_semantics():
    with pytest.raises(SpecError, match="nu must be a positive"):
        compile_spec(parse("x > 0"), "new", nu=0)
    with pytest.raises(SpecError, match="unknown semantics"):
        compile_spec(parse("x > 0"), "fuzzy")


@pytest.mark.parametrize("nu", [0.5, 1.0, 2.0, 30.0, 500.0])
def test_new_conjunction_of_operands_equals_the_stacked_one(nu):
    """`new_conjunction_of` (operand by operand, as `&` and `|` take it) against `new_conjunction`
    of the stacked operands: signs, zeros, ties, infinities, magnitudes from 1e-300 to 1e300."""
    rng = np.random.default_rng(int(nu * 10))
    for _ in range(200):
        count, shape = int(rng.integers(1, 7)), (int(rng.integers(1, 4)), int(rng.integers(1, 50)))
        values = rng.normal(size=(count,) + shape) * rng.choice([1e-300, 1e-3, 1.0, 1e300])
        values[rng.random(values.shape) < 0.1] = 0.0
        values[rng.random(values.shape) < 0.05] = np.inf
        values[rng.random(values.shape) < 0.03] = -np.inf
        if rng.random() < 0.3:
            values = np.round(values)
        with np.errstate(all="ignore"):
            expected = kernels.new_conjunction(np.stack(list(values), axis=-1), nu)
        actual = kernels.new_conjunction_of(list(values), nu)
        assert np.array_equal(np.isnan(actual), np.isnan(expected))
        finite = np.isfinite(expected)
        assert np.array_equal(actual[~finite], expected[~finite], equal_nan=True)
        assert np.allclose(actual[finite], expected[finite], rtol=1e-12, atol=0)
