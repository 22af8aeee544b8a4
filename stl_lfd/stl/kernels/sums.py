"""Running and tail sums of the new conjunction's terms, one run per owner (the operand that is a
candidate's minimum).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from stl_lfd.stl.kernels import budgets
from stl_lfd.stl.kernels.interpolation import _interpolated_tail_sums
from stl_lfd.stl.kernels.memory import _blocks, _pad
from stl_lfd.stl.kernels.terms import _factored_constants, _factored_terms, _terms


@dataclass(frozen=True)
class _Runs:
    """Running sums of weights and numerators, one run per owner: the sums of its first t terms
    (t >= 1) are `sums[:, offsets[owner] + t - 1]` times `factors[:, owner]`."""

    sums: np.ndarray  # 2 x total
    offsets: np.ndarray  # owners
    factors: np.ndarray  # 2 x owners


def _cumulative_sums(values: np.ndarray, rows: np.ndarray, starts: np.ndarray, lengths: np.ndarray, scales: np.ndarray, nu: float) -> _Runs:
    """Running sums of the terms of values[row, start], values[row, start + 1], ... for
    `length` samples, one run per owner (rows, starts, lengths, scales: owners).

    Runs are taken by length in blocks of owners x samples, padded to the block's longest;
    samples past a run are read but never summed into it, so they may be anything.
    """
    order = np.argsort(lengths, kind="stable")
    order = order[lengths[order] > 0]
    blocks = _blocks(lengths[order], budgets.BLOCK_ELEMENTS)
    spans = np.array([int(lengths[order[block][-1]]) for block in blocks], dtype=np.int64)
    sizes = np.array([block.stop - block.start for block in blocks], dtype=np.int64) * spans
    sums = np.empty((2, int(sizes.sum())))
    offsets = np.zeros(lengths.size, dtype=np.int64)
    factors = np.ones((2, lengths.size))
    if order.size == 0:
        return _Runs(sums, offsets, factors)
    windows = sliding_window_view(_pad(values, values.shape[-1] + int(spans[-1]), np.inf), int(spans[-1]), axis=-1)
    factored = nu <= budgets.FACTORED_NU_MAX and np.all(np.isfinite((1 + nu) / np.abs(scales)))
    if factored:  # the terms below are exp(-nu x) and its numerator up to these constants
        factors = _factored_constants(scales, nu)
    base = 0
    for block, span, size in zip(blocks, spans, sizes):
        owners = order[block]
        terms = sums[:, base : base + size].reshape(2, -1, span)
        offsets[owners] = base + np.arange(owners.size) * span
        base += size
        segment = windows[rows[owners], starts[owners], :span]
        if factored:
            _factored_terms(segment, scales[owners], nu, out=terms)
        else:
            terms[...] = _terms(segment, scales[owners, None], nu)
        np.cumsum(terms, axis=-1, out=terms)
    return _Runs(sums, offsets, factors)


def _tail_sums(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """`2 x owners` sums of the terms of left[row, start .. end-1] under each owner's scale
    (0 where end <= start). Every sample summed is above its owner's scale.

    Owners that sum many samples take them by interpolation where it is exact to rounding
    (`_interpolated_tail_sums`), the others term by term.
    """
    lengths = ends - start
    long = np.flatnonzero(lengths >= 4 * budgets.POINT_COUNTS[0])
    # interpolation costs at least the fewest points times the longest sum
    if long.size == 0 or lengths[long].sum() < budgets.POINT_COUNTS[0] * budgets.INTERPOLATION_COST * lengths.max():
        return _direct_tail_sums(left, rows, start, ends, scales, nu)
    sums = np.empty((2, ends.size))
    sums[:, long], taken = _interpolated_tail_sums(left, rows[long], start, ends[long], scales[long], nu)
    direct = np.ones(ends.size, dtype=bool)
    direct[long[taken]] = False
    rest = np.flatnonzero(direct)
    sums[:, rest] = _direct_tail_sums(left, rows[rest], start, ends[rest], scales[rest], nu)
    return sums


def _direct_tail_sums(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """`_tail_sums` term by term.

    Owners are taken by sign and by end, in blocks of owners x samples: the samples before the
    block's first end belong to every owner of the block.
    """
    sums = np.zeros((2, ends.size))
    for negative in (True, False):
        group = np.flatnonzero((ends > start) & ((scales < 0) == negative))
        group = group[np.argsort(ends[group], kind="stable")]
        for block in _blocks(ends[group] - start, budgets.BLOCK_ELEMENTS):
            owners = group[block]
            sums[:, owners] = _tail_block(left, rows[owners], start, ends[owners], scales[owners], nu)
    return sums


def _tail_block(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """`_tail_sums` for owners of one sign, sorted by end: `2 x k`."""
    stop, shared = int(ends[-1]), int(ends[0])
    one_row = rows[0] == rows[-1] and np.all(rows == rows[0])
    values = left[rows[0], start:stop] if one_row else left[rows, start:stop]  # (k x) samples
    past = np.arange(shared, stop) >= ends[:, None]  # k x (stop - shared)
    magnitudes = np.abs(scales)[:, None]
    if nu > budgets.FACTORED_NU_MAX or not np.all(np.isfinite((1 + nu) / magnitudes)):
        values = np.array(np.broadcast_to(values, (ends.size, stop - start)))
        values[:, shared - start :][past] = np.inf
        return _terms(values, scales[:, None], nu).sum(axis=-1)

    def exponentials(rate: float) -> np.ndarray:
        """exp(-rate v / |m|), 0 past each owner's end: exp(-rate x) up to a constant."""
        exponent = np.multiply.outer(-rate / magnitudes[:, 0], values) if one_row else values * (-rate / magnitudes)
        np.copyto(exponent[:, shared - start :], -np.inf, where=past)
        return np.exp(exponent, out=exponent)

    ones = np.ones(stop - start)
    weights = exponentials(nu)
    totals = weights @ ones
    if scales[0] < 0:  # -nu x = -nu v / |m| - nu
        numerators = np.square(weights, out=weights) @ ones if nu == 1 else exponentials(1 + nu) @ ones
        return np.stack([totals * np.exp(-nu), numerators * np.exp(-(1 + nu))])
    finite = np.where(np.isfinite(values), values, 0.0)  # -nu x = -nu v / m + nu
    numerators = weights @ finite if one_row else np.einsum("ij,ij->i", weights, finite)
    return np.stack([totals, numerators]) * np.exp(nu)
