"""Bounded `G`/`F` windows under the new robustness: wide windows at many outputs take the
interpolation of `kernels.windows._interpolated_windows` where it is exact; each window against its
new conjunction taken directly."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from stl_lfd.stl import compile_spec, parse
from stl_lfd.stl.kernels import budgets, interpolation, new_conjunction, new_windows
from stl_lfd.stl.kernels.memory import _pad

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")


def direct_windows(values: np.ndarray, width: int, count: int, nu: float) -> np.ndarray:
    """The new conjunction of each window, operand by operand (+inf past the end)."""
    windows = sliding_window_view(_pad(values, count + width - 1, np.inf), width, axis=-1)[..., :count, :]
    return new_conjunction(windows, nu)


def signal(rng: np.random.Generator, kind: int, shape: tuple[int, int]) -> np.ndarray:
    """Smooth, positive, rough, held, or negative signals; sometimes with infinities or rounded."""
    rows, samples = shape
    if kind == 0:
        values = np.cumsum(rng.normal(0, 0.01, shape), axis=-1) + rng.normal(0, 0.2)
    elif kind == 1:
        values = np.abs(np.cumsum(rng.normal(0, 0.02, shape), axis=-1)) + 0.01
    elif kind == 2:
        values = rng.normal(0, 1, shape)
    elif kind == 3:
        values = np.repeat(rng.normal(0, 0.1, (rows, samples // 8 + 1)), 8, axis=-1)[:, :samples]
    else:
        values = -np.abs(np.cumsum(rng.normal(0, 0.01, shape), axis=-1)) - 0.001
    if rng.random() < 0.2:
        values[rng.random(shape) < 0.02] = np.inf
    if rng.random() < 0.1:
        values[rng.random(shape) < 0.01] = -np.inf
    if rng.random() < 0.1:
        values = np.round(values, 1)  # zero minima and samples on nodes
    return values


def difference(actual: np.ndarray, expected: np.ndarray) -> float:
    assert not np.isnan(actual).any()
    assert np.array_equal(np.isinf(actual), np.isinf(expected)) and np.array_equal(actual[np.isinf(actual)], expected[np.isinf(expected)])
    finite = np.isfinite(expected)
    return float(np.max(np.abs(actual[finite] - expected[finite]) / np.maximum(1.0, np.abs(expected[finite])), initial=0.0))


@pytest.mark.parametrize("free", [False, True], ids=["costed", "interpolation free"])
@pytest.mark.parametrize("seed", range(4))
def test_wide_windows_match_the_direct_conjunction(seed, free, monkeypatch):
    """Windows of 64-400 samples over 100-900, at 2 outputs to all: 50 cases a seed."""
    if free:  # taken wherever the bound allows
        monkeypatch.setattr(budgets, "WINDOW_INTERPOLATION_COST", 0)
    rng = np.random.default_rng(seed)
    for case in range(50):
        samples = int(rng.integers(100, 900))
        values = signal(rng, case % 5, (int(rng.integers(1, 4)), samples))
        nu = float(rng.choice([0.5, 1.0, 2.0, 5.0, 30.0]))
        width, count = int(rng.integers(64, min(samples, 400) + 1)), int(rng.integers(2, samples + 1))
        with np.errstate(all="ignore"):
            expected = direct_windows(values, width, count, nu)
        actual = new_windows(values, width, count, nu)
        assert actual.shape == expected.shape
        assert difference(actual, expected) <= 1e-12


def test_the_interpolation_is_taken_on_a_trajectory():
    """A smooth 2,200-sample signal: most of its 500-sample windows interpolate, exactly."""
    rng = np.random.default_rng(5)
    values = np.cumsum(rng.normal(0, 0.002, (1, 2200)), axis=-1) + 0.3
    taken = []
    original = interpolation._node_sums

    def counting(nodes, counts, scales, nu):
        taken.append(scales.size)
        return original(nodes, counts, scales, nu)

    interpolation._node_sums = counting
    try:
        actual = new_windows(values, 500, 2200, 1.0)
    finally:
        interpolation._node_sums = original
    assert sum(taken) > 1100
    assert difference(actual, direct_windows(values, 500, 2200, 1.0)) <= 1e-12


def test_formulas_with_wide_windows_match(monkeypatch):
    """`G`, `F` and a window under an until, batched, against windows taken directly."""
    rng = np.random.default_rng(2)
    times = np.arange(900) / 100
    signals = {name: np.cumsum(rng.normal(0, 0.01, size=(2, times.size)), axis=-1) for name in "xy"}
    for text in ("G[0, 2] x > -0.1", "F[0.5, 3] (x > 0 & y < 0.1)", "(G[0, 1] x > -0.2) U y > 0.05"):
        actual = compile_spec(parse(text), "new").trace(signals, times)
        monkeypatch.setattr(budgets, "INTERPOLATED_WIDTH_MIN", 10**9)
        expected = compile_spec(parse(text), "new").trace(signals, times)
        monkeypatch.undo()
        assert difference(actual, expected) <= 1e-12
