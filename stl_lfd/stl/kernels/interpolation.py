"""Long sums of the new conjunction's terms by interpolation at Chebyshev points, where it is exact
to rounding.

The tail sums of one row's owners all sum the same samples v_k, each owner m its own function
f(v) = exp(-a (v - m)) (a = nu / |m| for weights, (1 + nu) / |m| for the numerators of a
negative m; v exp(-a (v - m)) for those of a positive one). Interpolated at R Chebyshev
points t_r of the row's range [lo, hi], f(v) = sum_r f(t_r) l_r(v) with the Lagrange basis
l_r, so that sum_{k < e} f(v_k) = sum_r f(t_r) L_r(e) with L_r(e) = sum_{k < e} l_r(v_k):
running sums of the basis, once per row, and R terms per owner instead of e. At Chebyshev
points the error is at most 2 ((hi - lo) / 4)^R max |f^(R)| / R! per sample, where
max |f^(R)| = a^R exp(a (m - lo)) (times (R / a + max |v|) for v exp(..)): an owner takes the
interpolation when, for each of its two sums at its own rate, its samples' errors add up to
at most `budgets.INTERPOLATION_ERROR` next to its own term (1, or m for a positive numerator), and
when f stays within e^2 at the nodes (rounding); the others sum term by term. A row takes
it only where it costs less.
Bounded windows under the new robustness (`_interpolated_windows`) do the same with the
windows' minima as owners: a window's sums are differences of two running sums.
"""

from __future__ import annotations

import math

import numpy as np

from stl_lfd.stl.kernels import budgets
from stl_lfd.stl.kernels.terms import _factored_constants, _factored_terms


def _interpolated_tail_sums(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """`_tail_sums` by interpolation where it is within `budgets.INTERPOLATION_ERROR`: the sums
    (`2 x owners`, garbage where not taken) and the mask of the owners taken."""
    present = np.zeros(left.shape[0], dtype=bool)
    present[rows] = True
    used_rows = np.flatnonzero(present)
    row_index = (np.cumsum(present) - 1)[rows]
    stops = np.full(used_rows.size, start)
    np.maximum.at(stops, row_index, ends)
    values = np.array(left[used_rows, start : int(stops.max())])
    values[np.arange(values.shape[-1]) >= (stops - start)[:, None]] = np.inf  # no owner sums these
    lows, highs = _finite_range(values)
    points, taken = _points_taken(row_index, lows, highs, ends - start, stops - start, scales, nu, budgets.INTERPOLATION_COST)
    sums = np.zeros((2, ends.size))
    owners = np.flatnonzero(taken)
    sums[:, owners] = _interpolated_sums(
        values, lows, highs, points, row_index[owners], np.zeros(owners.size, dtype=int), ends[owners] - start, scales[owners], nu
    )
    return sums, taken


def _finite_range(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest finite value of each row of `rows x samples` (0 and 0 for none)."""
    finite = np.isfinite(values)
    any_finite = finite.any(axis=-1)
    lows = np.where(any_finite, np.where(finite, values, np.inf).min(axis=-1), 0.0)
    highs = np.where(any_finite, np.where(finite, values, -np.inf).max(axis=-1), 0.0)
    return lows, highs


def _points_taken(
    row_index: np.ndarray, lows: np.ndarray, highs: np.ndarray, lengths: np.ndarray, spans: np.ndarray, scales: np.ndarray, nu: float, cost: float
) -> tuple[np.ndarray, np.ndarray]:
    """The points each row interpolates at (`rows`, 0: none, see `_row_points`) and the mask of
    the owners (`owners`: their rows, the terms each sums, their scales) that take them: those
    for which the row's points are exact enough."""
    needed = _points_needed(lows[row_index], highs[row_index], lengths, scales, nu)
    points = _row_points(row_index, needed, lengths, spans, cost)
    return points, (needed > 0) & (needed <= points[row_index])


def _interpolated_sums(
    values: np.ndarray,
    lows: np.ndarray,
    highs: np.ndarray,
    points: np.ndarray,
    owner_rows: np.ndarray,
    firsts: np.ndarray,
    stops: np.ndarray,
    scales: np.ndarray,
    nu: float,
) -> np.ndarray:
    """Weights and numerators (`2 x owners`) of each owner's terms over values[row, first :
    stop], interpolated at its row's `points` Chebyshev points of [low, high]. Rows are taken by
    number of points, in chunks whose running sums stay within `budgets.CACHED_ELEMENTS`.

    Args:
        values: `rows x samples`, +inf where no owner sums; lows, highs, points: `rows`.
        owner_rows, firsts, stops, scales: `owners`, whose rows have points.
    """
    sums = np.zeros((2, owner_rows.size))
    from_start = not firsts.any()  # tail sums: L_r(0) = 0 need not be subtracted
    for count in sorted(set(points[points > 0].tolist())):  # np.unique costs more on a few rows
        group = np.flatnonzero(points == count)
        nodes = _chebyshev_nodes(lows[group], highs[group], count)  # rows x R
        local = np.full(points.size, -1)
        local[group] = np.arange(group.size)
        members = np.flatnonzero(local[owner_rows] >= 0)
        members = members[np.argsort(local[owner_rows[members]], kind="stable")]
        member_rows = local[owner_rows[members]]
        step = max(1, budgets.CACHED_ELEMENTS // (count * values.shape[-1]))
        bounds = np.searchsorted(member_rows, np.arange(0, group.size + step, step))
        for chunk, begin in enumerate(range(0, group.size, step)):
            owners, rows = members[bounds[chunk] : bounds[chunk + 1]], member_rows[bounds[chunk] : bounds[chunk + 1]]
            running = _running_basis_sums(values[group[begin : begin + step]], nodes[begin : begin + step])  # (samples + 1) x rows x R
            flat = running.reshape(-1, count)  # ((samples + 1) x rows) x R: np.take is faster than [stops, rows]
            chunk_rows = running.shape[1]
            counts = np.take(flat, stops[owners] * chunk_rows + rows - begin, axis=0)  # owners x R
            if not from_start:
                counts -= np.take(flat, firsts[owners] * chunk_rows + rows - begin, axis=0)
            sums[:, owners] = _node_sums(nodes[rows], counts, scales[owners], nu)
    return sums


def _row_points(row_index: np.ndarray, needed: np.ndarray, lengths: np.ndarray, spans: np.ndarray, cost: float) -> np.ndarray:
    """Number of points of each row (0: none), the cheapest: each point costs `cost` times the
    row's span and its owners' count, owners that need more sum their terms one by one.

    Args:
        row_index: `owners` rows; needed: `owners` points each needs (0: none will do);
        lengths: `owners` terms each sums; spans: `rows` samples each row's sums run over.
    """
    counts = np.array(budgets.POINT_COUNTS)
    rows, kinds = spans.size, counts.size + 1
    kind = np.where(needed > 0, np.searchsorted(counts, needed), counts.size)  # counts.size: none
    cell = row_index * kinds + kind
    owners = np.cumsum(np.bincount(cell, minlength=rows * kinds).reshape(rows, kinds), axis=1)[:, :-1]
    covered = np.cumsum(np.bincount(cell, lengths, minlength=rows * kinds).reshape(rows, kinds), axis=1)
    totals = covered[:, -1:]
    costs = np.hstack([totals, counts * (spans[:, None] + owners) * cost + totals - covered[:, :-1]])
    return np.concatenate([[0], counts])[np.argmin(costs, axis=1)]


def _chebyshev_nodes(lows: np.ndarray, highs: np.ndarray, count: int) -> np.ndarray:
    """`rows x count` Chebyshev points (first kind) of each row's [low, high]."""
    angles = (2 * np.arange(count) + 1) * np.pi / (2 * count)
    return (lows + highs)[:, None] / 2 + (highs - lows)[:, None] / 2 * np.cos(angles)


def _points_needed(lows: np.ndarray, highs: np.ndarray, counts: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """The fewest of `budgets.POINT_COUNTS` points at which interpolating each owner's sums over [low,
    high] errs by at most `budgets.INTERPOLATION_ERROR` over its `counts` samples, next to its own term
    (bound above, in logarithms): the weights at rate nu / |m| and the numerators, at (1 + nu)
    / |m| for a negative m, v exp(-nu (v - m) / |m|) for a positive one (whose derivatives carry
    |v| + R / a, next to its own term m). 0 where none does, or where the node values would be
    too large."""
    magnitudes = np.abs(scales)
    negative = scales < 0
    weight_rates = nu / magnitudes
    numerator_rates = np.where(negative, (1 + nu) / magnitudes, weight_rates)
    too_many = budgets.POINT_COUNTS[-1] + 1
    with np.errstate(all="ignore"):
        base = math.log(budgets.INTERPOLATION_ERROR) - np.log(2 * np.maximum(counts, 1))
        peak = np.maximum(np.maximum(np.abs(lows), np.abs(highs)), magnitudes)
        numerator_scale = np.where(negative, 0.0, np.log((peak + budgets.POINT_COUNTS[-1] / weight_rates) / magnitudes))
        needed = _fewest_points(numerator_rates, numerator_scale, lows, highs, scales, base)
        # Where m >= low the numerators' bound is the stricter (a rate at least the weights',
        # a scale at least 0): the weights' is checked only below the range.
        below = np.flatnonzero(scales < lows)
        if below.size:
            weights_needed = _fewest_points(weight_rates[below], 0.0, lows[below], highs[below], scales[below], base[below])
            needed[below] = np.maximum(needed[below], weights_needed)
        # the larger rate is the numerators': exp(a (m - low)) at the nodes within e^2
        values_bounded = (numerator_rates * (scales - lows) <= budgets.NODE_VALUE_LOG_MAX) & (nu <= budgets.FACTORED_NU_MAX)
    needed[(needed == too_many) | ~values_bounded | ~(highs > lows)] = 0
    np.copyto(needed, budgets.POINT_COUNTS[0], where=(highs == lows) & values_bounded)  # one value: exact
    return needed


def _fewest_points(rates: np.ndarray, scale: np.ndarray | float, lows: np.ndarray, highs: np.ndarray, scales: np.ndarray, base: np.ndarray) -> np.ndarray:
    """The fewest of `budgets.POINT_COUNTS` for which the bound of `_points_needed` holds for one sum
    at `rates` (its derivatives times exp(`scale`)), or one more than the most."""
    margin = base - rates * (scales - lows) - scale
    log_reach = np.log(rates * (highs - lows) / 4)
    fewest = np.full(scales.size, budgets.POINT_COUNTS[-1] + 1)
    for count, log_factorial in zip(budgets.POINT_COUNTS[::-1], budgets.LOG_FACTORIALS[::-1]):  # a count at a time: fast on many owners
        np.copyto(fewest, count, where=count * log_reach - log_factorial <= margin)
    return fewest


def _running_basis_sums(values: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """L_r(e) = sum_{k < e} l_r(values[k]) for the Lagrange basis at `nodes` (Chebyshev,
    barycentric weights (-1)^r sin((2r+1) pi / 2R)); +inf samples count 0.

    Args:
        values: `rows x samples`.
        nodes: `rows x R`.

    Returns:
        `(samples + 1) x rows x R` array, L_r(0) = 0.
    """
    rows, samples = values.shape
    count = nodes.shape[-1]
    weights = (-1.0) ** np.arange(count) * np.sin((2 * np.arange(count) + 1) * np.pi / (2 * count))
    finite = np.isfinite(values).T  # samples x rows
    all_finite = bool(finite.all())
    blocks = -(-samples // budgets.RUNNING_BLOCK)
    padded = np.zeros((blocks * budgets.RUNNING_BLOCK, rows, count))
    basis = padded[:samples]
    between = (nodes[:, 0] + nodes[:, 1]) / 2  # inside the range, on no node: stands for +inf
    np.subtract((values.T if all_finite else np.where(finite, values.T, between))[:, :, None], nodes, out=basis)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(weights, basis, out=basis)
        totals = np.einsum("srk->sr", basis)  # samples x rows (faster than sum along a short axis)
    on_node = ~np.isfinite(totals)  # a sample on a node (to rounding): its basis is one-hot there
    if on_node.any():
        sample, row = np.nonzero(on_node)
        nearest = np.argmin(np.abs(np.where(finite[sample, row], values[row, sample], between[row])[:, None] - nodes[row]), axis=-1)
        basis[sample, row] = np.arange(count) == nearest[:, None]
        totals[on_node] = 1.0
    basis *= (1 / totals if all_finite else finite / totals)[:, :, None]
    running = np.empty((blocks * budgets.RUNNING_BLOCK + 1, rows, count))
    running[0] = 0.0
    shaped = running[1:].reshape(blocks, budgets.RUNNING_BLOCK, rows * count)
    np.matmul(budgets.LOWER_ONES, padded.reshape(blocks, budgets.RUNNING_BLOCK, rows * count), out=shaped)
    shaped[1:] += np.cumsum(shaped[:-1, -1], axis=0)[:, None]
    return running[: samples + 1]


def _node_sums(nodes: np.ndarray, counts: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """Weights and numerators (`2 x owners`) from each owner's terms at its row's nodes
    (`owners x R`) and the running basis sums there (`counts`, `owners x R`).

    The terms are taken factored (`_factored_terms`): the nodes are at most
    budgets.NODE_VALUE_LOG_MAX below m and nu at most budgets.FACTORED_NU_MAX, so nothing overflows.
    """
    terms = np.empty((2,) + nodes.shape)
    _factored_terms(nodes, scales, nu, out=terms)
    return np.einsum("wor,or->wo", terms, counts) * _factored_constants(scales, nu)
