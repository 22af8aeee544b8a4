"""The terms of the new conjunction's sums: weights exp(-nu x) and numerator terms of operands
whose minimum is known.
"""

from __future__ import annotations

import numpy as np


def _terms(values: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """Weights exp(-nu x) and numerator terms of operands `values` of conjunctions whose minimum
    is `scales` (finite, nonzero; broadcast against `values`), x = (v - m) / |m|.

    The numerator term is exp(-(1 + nu) x) for m < 0 and v exp(-nu x) for m > 0; an +inf
    operand gives 0 to both.

    Returns:
        `2 x ...` array: weights, numerators.
    """
    terms = np.empty((2,) + np.broadcast_shapes(np.shape(values), np.shape(scales)))
    weights, numerators = terms
    excess = np.subtract(values, scales, out=numerators)
    excess /= np.abs(scales)
    np.multiply(excess, -nu, out=weights)
    np.exp(weights, out=weights)
    if nu == 1:  # e^-x, the factor of a negative minimum's numerator
        np.copyto(numerators, weights)
    else:
        np.negative(excess, out=numerators)
        np.exp(numerators, out=numerators)
    if np.isposinf(values).any():
        values = np.where(values == np.inf, 0.0, values)
    np.copyto(numerators, values, where=scales > 0)
    numerators *= weights
    return terms


def _factored_constants(scales: np.ndarray, nu: float) -> np.ndarray:
    """`2 x k`: the constants `_factored_terms`' weights and numerators are multiplied by to be
    `_terms`' (-nu x = -nu v / |m| -+ nu, and -(1 + nu) x for a negative numerator)."""
    negative = scales < 0
    return np.exp(np.stack([np.where(negative, -nu, nu), np.where(negative, -(1 + nu), nu)]))


def _factored_terms(values: np.ndarray, scales: np.ndarray, nu: float, out: np.ndarray) -> None:
    """`_terms` of `k x n` operands under `k` scales, each row divided by a constant: weights
    exp(-nu v / |m|) and numerators exp(-(1 + nu) v / |m|) (m < 0) or v exp(-nu v / |m|) (m > 0),
    into `out` (`2 x k x n`). Needs nu <= budgets.FACTORED_NU_MAX and (1 + nu) / |m| finite."""
    weights, numerators = out
    magnitudes = np.abs(scales)[:, None]
    np.multiply(values, -nu / magnitudes, out=weights)
    np.exp(weights, out=weights)
    negative = scales < 0
    if nu == 1:
        np.copyto(numerators, weights)
    else:
        np.multiply(values, -1 / magnitudes, out=numerators)
        np.exp(numerators, out=numerators)
    if not negative.all():
        finite = np.where(values == np.inf, 0.0, values) if np.isposinf(values).any() else values
        np.copyto(numerators, finite, where=~negative[:, None])
    numerators *= weights
