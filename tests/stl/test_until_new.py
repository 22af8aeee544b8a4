"""Until under the new robustness: the owner-sharing kernel of `kernels.new_until` against
the straightforward one it replaced (a `width x width` operand matrix per output), kept here as
`reference_until`."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from stl_lfd.signals import read_signal_csv
from stl_lfd.stl import compile_spec, parse
from stl_lfd.stl.kernels import budgets, classic_until, interpolation, new_conjunction, new_disjunction, new_until, sums
from stl_lfd.stl.kernels import semantics as kernel_semantics
from stl_lfd.stl.kernels.memory import _pad
from tests.conftest import ROOT

pytestmark = [pytest.mark.filterwarnings("ignore::stl_lfd.stl.robustness.HorizonWarning"), pytest.mark.filterwarnings("error::RuntimeWarning")]

TOLERANCE = 1e-9
NUS = (0.5, 1.0, 2.0, 5.0)


# --- The reference: O(count x width^2) -----------------------------------------------------


def reference_until(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int, nu: float) -> np.ndarray:
    """`left U[lo, width-1] right` under the new robustness, as `new_until` computed it
    before: for each output, the new conjunction of every row of the `width x width` operand
    matrix (row j: left[i .. i+j-1], right[i+j], then +inf), then the new disjunction over j >= lo.

    Args:
        left, right: `... x n` arrays.

    Returns:
        `... x count` array.
    """
    length = count + width - 1
    left_windows = sliding_window_view(_pad(left, length, np.inf), width, axis=-1)
    right_windows = sliding_window_view(_pad(right, length, -np.inf), width, axis=-1)
    batch = int(np.prod(left.shape[:-1], dtype=int))
    step = max(1, budgets.CHUNK_ELEMENTS // max(1, batch * width * width))
    parts = []
    for begin in range(0, count, step):
        chunk = slice(begin, min(begin + step, count))
        lefts, rights = left_windows[..., chunk, :], right_windows[..., chunk, :]  # ... x c x width
        rows = np.arange(width)[:, None]
        columns = np.arange(width)[None, :]
        operands = np.where(columns < rows, lefts[..., None, :], np.inf)
        diagonal = np.broadcast_to(rights[..., :, None], operands.shape[:-1] + (1,))
        np.copyto(operands, np.broadcast_to(diagonal, operands.shape), where=columns == rows)
        candidates = new_conjunction(operands, nu)  # ... x c x width
        candidates[..., :lo] = -np.inf
        parts.append(new_disjunction(candidates, nu))
    return np.concatenate(parts, axis=-1)


def difference(actual: np.ndarray, expected: np.ndarray) -> float:
    """Largest difference, absolute below 1 and relative above; inf if infinities or NaNs differ."""
    if np.isnan(actual).any() or not np.array_equal(np.isinf(actual), np.isinf(expected)):
        return np.inf
    if not np.array_equal(actual[np.isinf(actual)], expected[np.isinf(expected)]):
        return np.inf
    finite = np.isfinite(expected)
    if not finite.any():
        return 0.0
    return float(np.max(np.abs(actual[finite] - expected[finite]) / np.maximum(1.0, np.abs(expected[finite]))))


def operands(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Random robustness values: mixed, all positive or all negative signs, rounded (zeros and
    ties), smooth or flat in stretches, at a random scale, with some +inf and -inf."""
    values = rng.normal(size=shape) * rng.choice([1e-3, 1.0, 1e3])
    kind = rng.integers(6)
    if kind == 1:
        values = np.abs(values)
    elif kind == 2:
        values = -np.abs(values)
    elif kind == 3:
        values = np.round(values)
    elif kind == 4:  # a smooth signal, as a trajectory gives
        values = np.cumsum(values, axis=-1) / 4
    elif kind == 5:  # flat stretches, as a held pose gives
        values = np.take(values, np.sort(rng.integers(0, shape[-1], shape[-1])), axis=-1)
    draw = rng.random(shape)
    values[draw < rng.choice([0.0, 0.05])] = np.inf
    values[draw > 1 - rng.choice([0.0, 0.03])] = -np.inf
    return values


def random_case(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, int, int, int, float]:
    batch = (int(rng.integers(1, 4)),) if rng.random() < 0.4 else ()
    samples = int(rng.integers(1, 30))
    left, right = operands(rng, batch + (samples,)), operands(rng, batch + (samples,))
    width = int(rng.integers(1, samples + 3))
    lo = int(rng.integers(0, width))
    count = int(rng.integers(1, samples + 1))
    return left, right, lo, width, count, float(rng.choice(NUS))


# --- Equality with the reference ------------------------------------------------------------


@pytest.mark.parametrize("seed", range(10))
def test_random_operands_match_the_reference(seed):
    """1,200 cases: bounded and unbounded windows, lo > 0, batches, infinities, zeros, signs."""
    rng = np.random.default_rng(seed)
    for _ in range(120):
        left, right, lo, width, count, nu = random_case(rng)
        with np.errstate(all="ignore"):
            expected = reference_until(left, right, lo, width, count, nu)
        actual = new_until(left, right, lo, width, count, nu)
        assert actual.shape == expected.shape
        assert difference(actual, expected) <= TOLERANCE, (left, right, lo, width, count, nu, actual, expected)


@pytest.mark.parametrize("seed", range(4))
def test_the_first_output_alone_matches_the_reference_and_the_first_of_two(seed):
    """600 cases of a top-level until (count 1, its own kernel) against the reference and
    against the first output of two (the general kernel), from 1 to 300 samples."""
    rng = np.random.default_rng(50 + seed)
    for case in range(150):
        left, right, lo, width, _, nu = random_case(rng)
        if case % 2:  # longer traces, where the sums are interpolated
            samples = int(rng.integers(100, 300))
            left, right = operands(rng, (2, samples)), operands(rng, (2, samples))
            width = int(rng.integers(1, samples + 3))
            lo = int(rng.integers(0, min(width, 3)))
        alone = new_until(left, right, lo, width, 1, nu)
        first_of_two = new_until(left, right, lo, width, 2, nu)[..., :1]
        assert difference(alone, first_of_two) <= 1e-12, (left, right, lo, width, nu)
        with np.errstate(all="ignore"):
            assert difference(alone, reference_until(left, right, lo, width, 1, nu)) <= TOLERANCE


@pytest.mark.parametrize("scale", [1e-300, 1e-308, 1e300, 1e150])
@pytest.mark.parametrize("nu", [1.0, 3.0, 40.0, 500.0])
def test_extreme_magnitudes_and_sharpness(scale, nu):
    """Minima near the limits of floating point, and nu beyond the factored exponentials."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        left, right = rng.normal(size=(2, 16)) * scale
        for count in (1, 4, 16):  # outputs near the start sum the rest of the window as totals
            with np.errstate(all="ignore"):
                expected = reference_until(left, right, 0, 13, count, nu)
            actual = new_until(left, right, 0, 13, count, nu)
            assert difference(actual / scale, expected / scale) <= TOLERANCE


def test_chunked_outputs_match(monkeypatch):
    """Outputs are computed in chunks; a tiny chunk size gives the same values."""
    rng = np.random.default_rng(3)
    left, right = rng.normal(size=(2, 2, 40))
    expected = new_until(left, right, 2, 30, 40, 1.0)
    monkeypatch.setattr(budgets, "CHUNK_ELEMENTS", 50)
    monkeypatch.setattr(budgets, "BLOCK_ELEMENTS", 7)
    assert difference(new_until(left, right, 2, 30, 40, 1.0), expected) <= 1e-12


def test_special_operands():
    """+inf operands drop out, -inf ones make a candidate -inf, a zero minimum gives 0."""
    nu = 1.0
    cases = [
        ([np.inf, np.inf], [np.inf, np.inf]),
        ([np.inf, 1.0], [-1.0, np.inf]),
        ([-np.inf, 2.0, 3.0], [1.0, 1.0, 1.0]),
        ([0.0, 1.0, 2.0], [3.0, -1.0, 2.0]),
        ([1.0, 2.0, 3.0], [-np.inf, -np.inf, -np.inf]),
        ([-1.0, -2.0, -3.0], [0.0, 5.0, -5.0]),
    ]
    for left, right in cases:
        left, right = np.array(left), np.array(right)
        for lo in range(left.size):
            expected = reference_until(left, right, lo, left.size, left.size, nu)
            actual = new_until(left, right, lo, left.size, left.size, nu)
            assert difference(actual, expected) <= TOLERANCE, (left, right, lo, actual, expected)


def test_classic_is_unchanged():
    left, right = np.random.default_rng(0).normal(size=(2, 20))
    actual = classic_until(left, right, 1, 5, 20)
    expected = [max(min([right[i + j]] + list(left[i : i + j])) for j in range(1, 5) if i + j < 20) if i + 1 < 20 else -np.inf for i in range(20)]
    assert np.array_equal(actual, expected)


# --- Inside formulas ------------------------------------------------------------------------

NESTED = [
    "x > 0.1 U y > 0",
    "x > 0 U[0.2, 0.6] y > 0.2",
    "G[0, 0.5] (x > -0.2 U[0, 0.4] y > 0)",
    "F[0.1, 0.7] (x > 0 U y > 0.3)",
    "(x > 0 U[0, 0.3] y > 0) U z > 0.1",
    "x > 0 U (y > 0 U[0.1, 0.5] z > 0)",
    "G[0, 0.3] x > -0.5 U (F[0.2, 0.4] y > 0 & z > -1)",
    "!(x > 0 U[0.3, 0.9] y > 0) | G[0.2, 0.5] z > 0",
]


def reference_evaluator(left, right, lo, width, count, nu):
    with np.errstate(all="ignore"):
        return reference_until(left, right, lo, width, count, nu)


@pytest.mark.parametrize("text", NESTED)
@pytest.mark.parametrize("nu", NUS)
def test_nested_formulas_match_the_reference(text, nu, monkeypatch):
    """Until inside G/F windows and other untils, batched `B x T` signals, every sample."""
    rng = np.random.default_rng(len(text))
    times = np.arange(24) / 20
    signals = {name: np.cumsum(rng.normal(0, 0.2, size=(3, times.size)), axis=-1) for name in "xyz"}
    compiled = compile_spec(parse(text), "new", nu)
    actual = compiled.trace(signals, times)
    monkeypatch.setattr(kernel_semantics, "new_until", reference_evaluator)
    expected = compile_spec(parse(text), "new", nu).trace(signals, times)
    assert difference(actual, expected) <= TOLERANCE


def test_a_long_trace_matches_the_reference():
    """2,200 samples (22 s at 100 Hz): the top-level value of an unbounded and a bounded until."""
    table = read_signal_csv(ROOT / "examples" / "three_regions.csv")
    times = np.arange(2200) / 100
    x, y, z = (np.interp(times, table.times, table.columns[name]) for name in "xyz")
    for left, right in ((x - 0.4, y - 0.15), (z - 0.39, x - 0.5)):  # z is constant: a flat left
        for lo, width, count in ((0, 2200, 1), (100, 400, 1), (0, 300, 40)):
            expected = reference_until(left, right, lo, width, count, 1.0)
            assert difference(new_until(left, right, lo, width, count, 1.0), expected) <= TOLERANCE


# --- Long sums by interpolation -------------------------------------------------------------


def owned_sums_case(rng: np.random.Generator, nu: float) -> tuple[np.ndarray, np.ndarray, int, np.ndarray, np.ndarray]:
    """Rows of 200-900 samples (smooth, rough, flat or with +inf) and owners (row, end) whose
    scale is below every sample they sum, at gaps from 1e-4 to 10 of their prefix minimum."""
    rows, samples = int(rng.integers(1, 5)), int(rng.integers(200, 900))
    kind = rng.integers(4)
    if kind == 0:
        left = np.cumsum(rng.normal(0, 0.01, (rows, samples)), axis=-1) + rng.normal(0, 0.2)
    elif kind == 1:
        left = rng.normal(0, 1, (rows, samples))
    elif kind == 2:
        left = np.repeat(rng.normal(0, 0.1, (rows, samples // 8 + 1)), 8, axis=-1)[:, :samples]
    else:
        left = np.abs(np.cumsum(rng.normal(0, 0.02, (rows, samples)), axis=-1)) + 0.01
        left[rng.random((rows, samples)) < 0.05] = np.inf
    start = int(rng.integers(0, 5))
    owner_rows = rng.integers(0, rows, 300)
    ends = rng.integers(start, samples + 1, 300)
    prefix = np.array([left[row, start:end].min(initial=np.inf) for row, end in zip(owner_rows, ends)])
    prefix = np.where(np.isfinite(prefix), prefix, 1.0)
    scales = prefix - np.abs(rng.normal(0, 0.05, 300)) * rng.choice([1e-4, 1e-2, 1.0, 10.0], 300) - 1e-12
    scales[scales == 0] = -1e-3
    return left, owner_rows, start, ends, scales


@pytest.mark.parametrize("seed", range(6))
def test_interpolated_sums_match_term_by_term(seed, monkeypatch):
    """Wherever the bound lets an owner take the interpolation (made free, so that it is taken
    wherever exact), its sums equal the direct ones next to its own term 1."""
    monkeypatch.setattr(budgets, "INTERPOLATION_COST", 0)
    rng = np.random.default_rng(seed)
    taken = 0
    for _ in range(40):
        nu = float(rng.choice((0.01, 0.1) + NUS + (30.0,)))
        left, rows, start, ends, scales = owned_sums_case(rng, nu)
        with np.errstate(all="ignore"):
            actual = sums._tail_sums(left, rows, start, ends, scales, nu)
            expected = sums._direct_tail_sums(left, rows, start, ends, scales, nu)
            taken += int(interpolation._interpolated_tail_sums(left, rows, start, ends, scales, nu)[1].sum())
        # next to the owner's own terms: weight 1, numerator 1 (negative m) or m (positive m)
        own = np.stack([np.ones(scales.size), np.where(scales < 0, 1.0, scales)])
        assert np.max(np.abs(actual - expected) / (own + np.abs(expected))) <= 1e-12
    assert taken > 2000  # of 12,000 owners: the interpolation was exercised


def test_owners_far_below_their_samples_at_small_nu():
    """A negative owner far below its samples, at small nu: its weights fall more slowly than its
    numerators, and each is bounded at its own rate (the numerators' bound does not cover them)."""
    samples = np.arange(600)
    left = 0.001 + 0.5 * (1 - np.cos(2 * np.pi * samples / 600))
    right = -2e-6 * (1 + 0.01 * np.sin(samples / 7))
    with np.errstate(all="ignore"):
        expected = reference_until(left, right, 0, 600, 1, 0.01)
    assert difference(new_until(left, right, 0, 600, 1, 0.01), expected) <= 1e-12
    left, right = 58 + 156 * np.arange(1000) / 1000, -np.ones(1000)
    for nu in (0.1, 0.5, 1.0):
        with np.errstate(all="ignore"):
            expected = reference_until(left, right, 0, 1000, 1, nu)
        assert difference(new_until(left, right, 0, 1000, 1, nu), expected) <= 1e-12


def test_an_owner_of_only_infinite_samples_in_a_constant_row(monkeypatch):
    """The row's one finite value far below an owner whose own samples are all +inf: no
    interpolation point may overflow (its sums are 0)."""
    monkeypatch.setattr(budgets, "INTERPOLATION_COST", 0)
    left = np.array([np.inf] * 150 + [-1000.0] * 150)[None]
    rows, ends, scales = np.array([0, 0]), np.array([150, 300]), np.array([0.01, -1001.0])
    actual = sums._tail_sums(left, rows, 0, ends, scales, 1.0)
    assert np.allclose(actual, sums._direct_tail_sums(left, rows, 0, ends, scales, 1.0), rtol=1e-12, atol=0)
    assert np.array_equal(actual[:, 0], [0.0, 0.0])


def test_interpolation_is_taken_only_where_it_pays():
    """One owner summing a long row sums term by term; 400 owners of one row interpolate."""
    rng = np.random.default_rng(1)
    left = np.cumsum(rng.normal(0, 0.002, (1, 1000)), axis=-1) + 1.0
    ends = np.arange(600, 1000)
    scales = np.minimum.accumulate(left[0])[ends - 1] - 0.5
    rows = np.zeros(ends.size, dtype=int)
    assert interpolation._interpolated_tail_sums(left, rows, 0, ends, scales, 1.0)[1].all()
    assert not interpolation._interpolated_tail_sums(left, rows[:1], 0, ends[:1], scales[:1], 1.0)[1].any()


@pytest.mark.parametrize("seed", range(4))
def test_long_top_level_untils_match_the_reference(seed, monkeypatch):
    """Untils over 400-700 samples at their first outputs, on smooth traces that cross zero,
    batched: the candidates whose right operand owns them sum long prefixes by interpolation."""
    rng = np.random.default_rng(100 + seed)
    interpolated = []
    original = interpolation._node_sums
    monkeypatch.setattr(interpolation, "_node_sums", lambda nodes, counts, scales, nu: interpolated.append(scales.size) or original(nodes, counts, scales, nu))
    for free in (False, True):
        if free:
            assert sum(interpolated) > 300  # taken where it pays
            monkeypatch.setattr(budgets, "INTERPOLATION_COST", 0)
        for _ in range(3):
            samples = int(rng.integers(400, 700))
            left = np.cumsum(rng.normal(0, 0.01, (3, samples)), axis=-1) + rng.normal(0.2, 0.1)
            right = np.cumsum(rng.normal(0, 0.01, (3, samples)), axis=-1) + rng.normal(-0.2, 0.1)
            nu = float(rng.choice(NUS))
            count = int(rng.integers(1, 4))
            with np.errstate(all="ignore"):
                expected = reference_until(left, right, 0, samples, count, nu)
            actual = new_until(left, right, 0, samples, count, nu)
            assert difference(actual, expected) <= TOLERANCE
