"""Conjunctions and disjunctions along the last axis: the classic minimum and the new robustness's
(Varnai & Dimarogonas), written once here.
"""

from __future__ import annotations

import math

import numpy as np

from stl_lfd.stl.kernels import budgets
from stl_lfd.stl.kernels.terms import _terms


def new_conjunction(values: np.ndarray, nu: float) -> np.ndarray:
    """The conjunction of Varnai & Dimarogonas along the last axis.

    With rho_min = min_i rho_i and rho~_i = (rho_i - rho_min) / rho_min:
        rho_min < 0:  sum_i rho_min exp(rho~_i) exp(nu rho~_i) / sum_i exp(nu rho~_i)
        rho_min > 0:  sum_i rho_i exp(-nu rho~_i) / sum_i exp(-nu rho~_i)
        rho_min = 0:  0
    +inf operands are left out (all +inf gives +inf); any -inf operand gives -inf.

    Args:
        values: `... x m` array of operand robustness values.
        nu: sharpness, > 0; the result tends to the minimum as nu grows.

    Returns:
        `...` array.
    """
    values = np.asarray(values, dtype=float)
    minimum = values.min(axis=-1, keepdims=True)  # ... x 1
    finite_minimum = np.isfinite(minimum)
    safe_minimum = np.where(finite_minimum & (minimum != 0), minimum, 1.0)
    all_finite = bool(finite_minimum.all()) and bool(np.isfinite(values.max()))  # two reductions, no mask
    finite = None if all_finite else np.isfinite(values)
    safe_values = values if all_finite else np.where(finite, values, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        # relative <= 0 for every finite operand where rho_min < 0, >= 0 where rho_min > 0: either
        # way exp(-nu |relative|) is the branch's weight (bit for bit), +inf operands drop out.
        # The ... x m temporaries are reused in place: these arrays are the kernels' largest.
        distance = np.subtract(safe_values, safe_minimum)
        distance /= safe_minimum
        np.abs(distance, out=distance)
        ratios = None if nu == 1 else np.exp(-distance)  # exp(relative) of the negative branch
        weights = np.exp(np.multiply(-nu, distance, out=distance), out=distance)
        if not all_finite:
            weights[~finite] = 0.0
        totals = np.sum(weights, axis=-1)
        product = np.multiply(weights, weights if ratios is None else ratios, out=ratios)
        negative = safe_minimum[..., 0] * np.sum(product, axis=-1) / totals
        positive = np.sum(np.multiply(safe_values, weights, out=product), axis=-1) / totals
    minimum = minimum[..., 0]
    result = np.where(minimum > 0, positive, np.where(minimum < 0, negative, 0.0))
    return np.where(np.isfinite(minimum), result, minimum)


def new_conjunction_of(operands: list[np.ndarray], nu: float) -> np.ndarray:
    """`new_conjunction` of a few arrays of one shape, operand by operand: the same values (to
    rounding), without stacking them (a short last axis reduces slowly).

    Args:
        operands: arrays of one shape `...`.
        nu: sharpness, > 0.

    Returns:
        `...` array.
    """
    if len(operands) > 4 and np.size(operands[0]) < budgets.STACKED_BELOW:  # many small operands: a loop would cost more
        return new_conjunction(np.stack(np.broadcast_arrays(*operands), axis=-1), nu)
    shape = np.broadcast_shapes(*(np.shape(operand) for operand in operands))
    size = math.prod(shape)
    if size <= budgets.CACHED_OPERAND_ELEMENTS:
        return _conjunction_of(operands, nu)
    flat = [np.broadcast_to(operand, shape).reshape(-1) for operand in operands]
    result = np.empty(size)
    for begin in range(0, size, budgets.CACHED_OPERAND_ELEMENTS):
        chunk = slice(begin, begin + budgets.CACHED_OPERAND_ELEMENTS)
        result[chunk] = _conjunction_of([operand[chunk] for operand in flat], nu)
    return result.reshape(shape)


def _conjunction_of(operands: list[np.ndarray], nu: float) -> np.ndarray:
    """`new_conjunction_of` on operands of one shape, all at once."""
    minimum = operands[0]
    for operand in operands[1:]:
        minimum = np.minimum(minimum, operand)
    usable = np.isfinite(minimum) & (minimum != 0)
    safe_minimum = np.where(usable, minimum, 1.0)
    magnitude = np.abs(safe_minimum)
    negative = minimum < 0
    any_negative, any_positive = bool(negative.any()), bool((minimum > 0).any())
    totals, below, above = np.zeros(minimum.shape), np.zeros(minimum.shape), np.zeros(minimum.shape)
    distance, weights = np.empty(minimum.shape), np.empty(minimum.shape)
    with np.errstate(over="ignore", invalid="ignore"):
        for operand in operands:
            np.subtract(operand, safe_minimum, out=distance)
            distance /= magnitude  # >= 0 where the minimum is usable; +inf operands drop out
            np.multiply(distance, -nu, out=weights)
            np.exp(weights, out=weights)
            totals += weights
            if any_negative:  # the negative branch's exp(relative) = exp(-distance) times the weight
                below += weights * (weights if nu == 1 else np.exp(-distance))
            if any_positive:
                above += weights * (operand if np.isfinite(operand).all() else np.where(np.isfinite(operand), operand, 0.0))
        result = np.where(negative, safe_minimum * below, above) / totals
    return np.where(usable, result, np.where(np.isfinite(minimum), 0.0, minimum))


def new_disjunction(values: np.ndarray, nu: float) -> np.ndarray:
    """`!(!a & !b & ...)` along the last axis."""
    return -new_conjunction(-np.asarray(values, dtype=float), nu)


def classic_conjunction(values: np.ndarray, nu: float = 0.0) -> np.ndarray:
    """Minimum along the last axis (`nu` is ignored; it keeps the signature of the new one)."""
    return np.min(values, axis=-1)


def _disjunction(values: np.ndarray, nu: float) -> np.ndarray:
    """`new_disjunction` along the last axis, computing only the branch each row takes: with
    M the maximum and x = (M - v) / |M|, M sum w e^-x / sum w for M > 0 and sum v w / sum w for
    M < 0, w = exp(-nu x); -inf operands drop out."""
    maximum = values.max(axis=-1)
    usable = np.isfinite(maximum) & (maximum != 0)  # else the maximum is the value
    scales = np.where(usable, -maximum, -1.0)
    weights, numerators = _terms(np.negative(values), scales[..., None], nu)  # the conjunction of -values
    ratio = numerators.sum(axis=-1) / weights.sum(axis=-1)
    return np.where(usable, -np.where(scales < 0, scales * ratio, ratio), maximum)
