"""`left U[lo, hi] right` at every output, under the classic and the new robustness.

Candidate (i, j) of `left U right` is the new conjunction of left[i .. i+j-1] and right[i+j].
With m its minimum and x_k = (v_k - m) / |m| >= 0 it is m N / D (m < 0) or N / D (m > 0),
D = sum_k exp(-nu x_k) and N = sum_k exp(-(1 + nu) x_k) (m < 0) or sum_k v_k exp(-nu x_k)
(m > 0): sums of positive terms of at most 1 (times v_k), so nothing overflows. Every term
depends on m through 1/m, so no sum carries over from one minimum to another: there is no
exact recursion over a growing window. But m is always one operand, the candidate's owner:
right[i+j] when it is below the prefix, else the first minimum q of the prefix. Each owner
sums its terms once, outward from itself, for every candidate it owns:
- right[i+j] sums left[i .. i+j-1] backwards: per output i a band of running sums over the
  chunk's outputs (samples < count) plus one total over the samples from count on;
- q does the same over left[i .. q-1], and keeps running sums forwards over left[q ..],
  shared by the owners of a flat stretch of equal minima.
The work is the owners' reach, at most (count + width) x width terms, where the matrix of
every candidate's operands cost count x width^2. A single output whose right operand stays
below left still needs its own sum for every j: width^2 / 2 terms, inherent to the formula.
The totals, the bulk of that case, are taken in cache-sized blocks of owners x samples.
A single output (a top-level until) has its own kernel, `_first_output_candidates`: all its
sums start at sample 0, so that every owner's is one tail sum, taken in one call.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import as_strided, sliding_window_view

from stl_lfd.stl.kernels import budgets
from stl_lfd.stl.kernels.conjunction import _disjunction
from stl_lfd.stl.kernels.memory import _pad
from stl_lfd.stl.kernels.sums import _cumulative_sums, _tail_sums
from stl_lfd.stl.kernels.terms import _terms


def classic_until(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int) -> np.ndarray:
    """`left U[lo, width-1] right` under the classic robustness at each of `count` outputs.

    For output i: the disjunction over j in [lo, width-1] of the conjunction of right[i + j]
    and left[i], ..., left[i + j - 1]. Samples past the end do not count.

    Args:
        left, right: `... x n` arrays aligned on the same samples, output i at sample i.
        lo: first window offset in samples.
        width: window length in samples (offsets 0 .. width-1).
        count: number of outputs.

    Returns:
        `... x count` array.
    """
    length = count + width - 1
    left_windows = sliding_window_view(_pad(left, length, np.inf), width, axis=-1)
    right_windows = sliding_window_view(_pad(right, length, -np.inf), width, axis=-1)
    batch = int(np.prod(left.shape[:-1], dtype=int))
    step = max(1, budgets.CHUNK_ELEMENTS // max(1, batch * width))
    parts = []
    for begin in range(0, count, step):
        chunk = slice(begin, min(begin + step, count))
        lefts, rights = left_windows[..., chunk, :], right_windows[..., chunk, :]  # ... x c x width
        before = np.minimum.accumulate(lefts, axis=-1)
        before = np.concatenate([np.full_like(before[..., :1], np.inf), before[..., :-1]], axis=-1)
        candidates = np.minimum(rights, before)
        candidates[..., :lo] = -np.inf
        parts.append(candidates.max(axis=-1))
    return np.concatenate(parts, axis=-1)


def new_until(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int, nu: float) -> np.ndarray:
    """`classic_until` under the new robustness with sharpness `nu`: `... x n` operands ->
    `... x count` (see the module's docstring for how)."""
    left, right = np.asarray(left, dtype=float), np.asarray(right, dtype=float)
    shape = left.shape[:-1]
    if lo >= width:
        return np.full(shape + (count,), -np.inf)
    length = count + width - 1
    left = _pad(left, length, np.inf)[..., :length].reshape(-1, length)
    right = _pad(right, length, -np.inf)[..., :length].reshape(-1, length)
    if count == 1:  # a top-level until: the first sample only
        with np.errstate(all="ignore"):
            return _disjunction(_first_output_candidates(left, right, lo, nu), nu).reshape(shape + (1,))
    step = max(1, budgets.CHUNK_ELEMENTS // (4 * left.shape[0] * width))
    parts = []
    for begin in range(0, count, step):
        outputs = min(step, count - begin)
        samples = slice(begin, begin + outputs + width - 1)
        with np.errstate(all="ignore"):  # entries that no candidate reads may overflow
            parts.append(_disjunction(_until_candidates(left[:, samples], right[:, samples], lo, width, outputs, nu), nu))
    return np.concatenate(parts, axis=-1).reshape(shape + (count,))


def _until_candidates(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int, nu: float) -> np.ndarray:
    """The new conjunction of left[i .. i+j-1] and right[i+j], for i < count and lo <= j < width.

    Args:
        left, right: `B x (count + width - 1)` arrays (padded with +inf and -inf).

    Returns:
        `B x count x (width - lo)` array.
    """
    before = _prefix_minima(left, width, count)  # B x count x width
    prefix_min = before[..., lo:]  # min of left[i .. i+j-1]: +inf for j = 0
    operand = sliding_window_view(right, width, axis=-1)[:, :count, lo:]  # right[i + j]
    minimum = np.minimum(prefix_min, operand)
    owned = np.isfinite(minimum) & (minimum != 0)  # -inf, +inf and 0 are their own values
    by_right = owned & (operand < prefix_min)
    values = _right_owned_ratios(left, right, by_right, lo, count, nu)  # garbage where not by_right
    at_left = np.flatnonzero(owned & ~by_right)
    if at_left.size:
        sums = _left_owned_sums(left, right, _first_minima(left, before), at_left, lo, count, nu)
        values.reshape(-1)[at_left] = sums[1] / sums[0]
    np.multiply(values, minimum, out=values, where=minimum < 0)
    np.copyto(values, minimum, where=~owned)
    return values


def _first_output_candidates(left: np.ndarray, right: np.ndarray, lo: int, nu: float) -> np.ndarray:
    """`_until_candidates` of the first output alone (count 1): `B x (width - lo)`.

    Every sum then starts at sample 0, so that each owner's is one tail sum, right's and
    left's owners in one call: right[j] over left[0 .. j-1]; left's first minimum q over
    left[0 .. q-1], plus running sums from q on (shared by the candidates it owns, up to the
    next lower sample) and right[j].
    """
    width = left.shape[-1]
    before = _prefix_minima(left, width, 1)  # B x 1 x width
    first = _first_minima(left, before)[:, 0, lo:]  # q
    prefix_min, operand = before[:, 0, lo:], right[:, lo:]
    minimum = np.minimum(prefix_min, operand)
    owned = np.isfinite(minimum) & (minimum != 0)  # -inf, +inf and 0 are their own values
    by_right = owned & (operand < prefix_min)
    right_rows, right_at = np.nonzero(by_right)
    left_rows, left_at = np.nonzero(owned & ~by_right)
    owners = left_rows * width + first[left_rows, left_at]  # sorted: q grows with j
    new_owner = np.diff(owners, prepend=-1) != 0
    starts = np.flatnonzero(new_owner)  # each owner's first candidate
    owner = np.cumsum(new_owner) - 1  # each candidate's owner
    owner_rows, positions = np.divmod(owners[starts], width)
    scales = np.concatenate([operand[right_rows, right_at], left[owner_rows, positions]])
    sums = _tail_sums(left, np.concatenate([right_rows, owner_rows]), 0, np.concatenate([right_at + lo, positions]), scales, nu)
    values = minimum.copy()
    if right_rows.size:  # right[j]'s own term: weight 1, numerator 1 (m < 0) or m
        own = np.where(scales[: right_rows.size] < 0, 1.0, scales[: right_rows.size])
        values[right_rows, right_at] = (sums[1, : right_rows.size] + own) / (sums[0, : right_rows.size] + 1.0)
    if left_rows.size:
        left_scales, tails = scales[right_rows.size :], sums[:, right_rows.size :]
        ends = left_at + lo  # each candidate's prefix is left[0 .. end-1]
        last = np.maximum.reduceat(ends, starts)
        forward = _cumulative_sums(left, owner_rows, positions, last - positions, left_scales, nu)
        run = forward.offsets[owner] + ends - positions[owner] - 1  # the sum over left[q .. end-1]
        left_sums = np.take(forward.sums, run, axis=1) * np.take(forward.factors, owner, axis=1)
        left_sums += np.take(tails, owner, axis=1) + _terms(right[left_rows, ends], left_scales[owner], nu)
        values[left_rows, left_at] = left_sums[1] / left_sums[0]
    np.multiply(values, minimum, out=values, where=owned & (minimum < 0))
    return values


def _prefix_minima(left: np.ndarray, width: int, count: int) -> np.ndarray:
    """Minimum of left[i .. i+j-1], +inf for j = 0: `B x count x width`, indexed by (row, i, j).

    Args:
        left: `B x (count + width - 1)` array.
    """
    windows = sliding_window_view(left, width, axis=-1)[:, :count]  # left[i + j]
    before = np.empty(windows.shape)
    before[..., 0] = np.inf
    np.minimum.accumulate(windows[..., :-1], axis=-1, out=before[..., 1:])
    return before


def _first_minima(left: np.ndarray, before: np.ndarray) -> np.ndarray:
    """The sample of the first occurrence of each prefix minimum `before` (from
    `_prefix_minima`): `B x count x width` ints, from j = 1 on."""
    count, width = before.shape[1:]
    windows = sliding_window_view(left, width, axis=-1)[:, :count]
    first = np.zeros(before.shape, dtype=np.int32)
    np.copyto(first[..., 1:], np.arange(width - 1, dtype=np.int32), where=windows[..., :-1] < before[..., :-1])
    np.maximum.accumulate(first, axis=-1, out=first)
    first += np.arange(count, dtype=np.int32)[:, None]
    return first


def _right_owned_ratios(left: np.ndarray, right: np.ndarray, by_right: np.ndarray, lo: int, count: int, nu: float) -> np.ndarray:
    """Numerator over weight sums of the candidates whose minimum is right[e], e = i + j: over
    left[i .. e-1] and right[e] itself. `B x count x (width - lo)`, garbage elsewhere.

    Per sample e: a total over left[count .. e-1] (where right[e] owns candidates) and, per
    output i, running sums over left[i .. min(e, count) - 1]; candidate (i, j) reads both
    through strided views.
    """
    batch, length = right.shape
    offsets = by_right.shape[-1]
    # right[e] owns some candidate exactly when it owns the one with the shortest prefix.
    samples = np.arange(lo, length)
    outputs = np.minimum(count - 1, samples - lo)
    owner = np.zeros((batch, length), dtype=bool)
    owner[:, lo:] = by_right[:, outputs, samples - outputs - lo]
    rows, positions = np.nonzero(owner)
    totals = np.zeros((2, batch, length))
    scales = right[rows, positions]
    totals[:, rows, positions] = _tail_sums(left, rows, count, positions, scales, nu)
    totals[0] += 1.0  # right[e] itself: x = 0
    totals[1] += np.where(right < 0, 1.0, right)
    heads = np.zeros((2, count, batch, length))
    values = left[:1, :count].T if batch == 1 else left[rows, :count].T
    heads[:, :, rows, positions] = _band_sums(values, scales, positions, nu)
    item = heads.itemsize
    # heads[:, i, b, i + lo + j] as [:, b, i, j]
    head_view = as_strided(
        heads.reshape(-1)[lo:], shape=(2, batch, count, offsets), strides=(count * batch * length * item, length * item, (batch * length + 1) * item, item)
    )
    total_view = sliding_window_view(totals, length - count + 1, axis=-1)[:, :, :count, lo:]
    numerators = np.add(head_view[1], total_view[1])
    numerators /= np.add(head_view[0], total_view[0])
    return numerators


def _left_owned_sums(left: np.ndarray, right: np.ndarray, first: np.ndarray, at: np.ndarray, lo: int, count: int, nu: float) -> np.ndarray:
    """Sums (weights, numerators) of the candidates at flat indices `at` of `B x count x (width -
    lo)`, whose minimum is the first minimum q of their prefix: over left[i .. q-1], left[q ..
    i+j-1] and right[i+j]. `2 x at.size`.

    Per owner q: a total over left[count .. q-1], running sums over left[i .. min(q, count) - 1]
    per output i, and running sums from q forwards, all shared by its candidates.
    """
    batch, length = left.shape
    rows, outputs, owners, ends = _left_owners(at, first, lo, count)
    keys = rows * length + owners
    last = np.full(batch * length, -1)  # per sample: the last sample of the longest prefix it owns
    np.maximum.at(last, keys, ends)
    used = np.flatnonzero(last >= 0)
    index = np.zeros(batch * length, dtype=np.int64)
    index[used] = np.arange(used.size)
    owner = index[keys]
    owner_rows = used // length
    positions = used - owner_rows * length
    scales = left.reshape(-1)[used]
    values = left[:1, :count].T if batch == 1 else left[owner_rows, :count].T
    heads = _band_sums(values, scales, positions, nu).reshape(2, -1)  # 2 x (count x owners)
    # Owners of equal value with no lower sample between them (a flat stretch of left) share
    # one run of forward sums from the first of them, q0: from q they are C(e) - C(q - 1).
    chained = np.zeros(used.size, dtype=bool)
    chained[1:] = (owner_rows[1:] == owner_rows[:-1]) & (scales[1:] == scales[:-1]) & (np.minimum.reduceat(left.reshape(-1), used)[:-1] == scales[:-1])
    chain = np.cumsum(~chained) - 1
    firsts = np.flatnonzero(~chained)
    starts = positions[firsts]
    forward = _cumulative_sums(left, owner_rows[firsts], starts, np.maximum.reduceat(last[used], firsts) - starts + 1, scales[firsts], nu)
    skipped = positions - starts[chain]  # terms of the chain before each owner
    factors = np.take(forward.factors, chain, axis=1)
    constants = _tail_sums(left, owner_rows, count, positions, scales, nu)
    constants -= np.where(skipped > 0, np.take(forward.sums, forward.offsets[chain] + np.maximum(skipped, 1) - 1, axis=1), 0.0) * factors
    bases = forward.offsets[chain] - starts[chain]  # run of C(e) at bases + e
    # gathers along the last axis: np.take is several times faster than [:, index] here
    sums = np.take(constants, owner, axis=1) + np.take(heads, outputs * used.size + owner, axis=1)
    sums += np.take(forward.sums, bases[owner] + ends, axis=1) * np.take(factors, owner, axis=1)
    sums += _terms(right.reshape(-1)[rows * length + ends + 1], scales[owner], nu)  # right[i + j]
    return sums


def _left_owners(at: np.ndarray, first: np.ndarray, lo: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Row, output i, owner sample q and last prefix sample i+j-1 of the candidates at flat
    indices `at` of `B x count x (width - lo)`."""
    width = first.shape[-1]
    row_output = at // (width - lo)
    offsets = at - row_output * (width - lo)
    rows = row_output // count
    outputs = row_output - rows * count
    owners = first.reshape(-1)[row_output * width + lo + offsets]
    return rows, outputs, owners, outputs + lo + offsets - 1


def _band_sums(values: np.ndarray, scales: np.ndarray, positions: np.ndarray, nu: float) -> np.ndarray:
    """Running sums, backwards over the first `count` samples, of the terms of left under the
    scales of owners at samples `positions`: at [:, i, ...] the sums over left[i .. min(p,
    count) - 1]. Garbage where those samples are not all above the scale.

    Args:
        values: `count x ...` left[i], broadcast against `scales` and `positions` (`...`).

    Returns:
        `2 x count x ...` array.
    """
    count = values.shape[0]
    terms = _terms(values, scales, nu)  # 2 x count x ...
    beyond = np.arange(count).reshape((count,) + (1,) * (terms.ndim - 2)) >= positions
    np.copyto(terms, 0.0, where=beyond)
    for sample in range(count - 2, -1, -1):  # a row at a time: faster than cumsum along an axis
        terms[:, sample] += terms[:, sample + 1]
    return terms
