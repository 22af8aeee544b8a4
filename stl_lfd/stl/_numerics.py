"""Numerical kernels of the robustness semantics: n-ary conjunctions and sliding windows.

All functions take and return float arrays; reductions run along the last axis. Infinite
operands stand for empty windows: +inf is the identity of a conjunction, -inf of a disjunction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import as_strided, sliding_window_view

# Largest number of array elements a windowed evaluation materialises at once.
_CHUNK_ELEMENTS = 1 << 22


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
    finite = np.isfinite(values)
    all_finite = bool(finite.all())
    safe_values = values if all_finite else np.where(finite, values, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        # relative <= 0 for every finite operand where rho_min < 0, >= 0 where rho_min > 0: either
        # way exp(-nu |relative|) is the branch's weight (bit for bit), +inf operands drop out.
        distance = np.abs((safe_values - safe_minimum) / safe_minimum)  # ... x m
        ratios = None if nu == 1 else np.exp(-distance)  # exp(relative) of the negative branch
        weights = np.exp(np.multiply(-nu, distance, out=distance))
        if not all_finite:
            weights[~finite] = 0.0
        ratios = weights if ratios is None else ratios
        totals = np.sum(weights, axis=-1)
        negative = safe_minimum[..., 0] * np.sum(weights * ratios, axis=-1) / totals
        positive = np.sum(safe_values * weights, axis=-1) / totals
    minimum = minimum[..., 0]
    result = np.where(minimum > 0, positive, np.where(minimum < 0, negative, 0.0))
    return np.where(np.isfinite(minimum), result, minimum)


# Operands of fewer elements than this, more than four of them, are stacked (measured).
_STACKED_BELOW = 128


def new_conjunction_of(operands: list[np.ndarray], nu: float) -> np.ndarray:
    """`new_conjunction` of a few arrays of one shape, operand by operand: the same values (to
    rounding), without stacking them (a short last axis reduces slowly).

    Args:
        operands: arrays of one shape `...`.
        nu: sharpness, > 0.

    Returns:
        `...` array.
    """
    if len(operands) > 4 and np.size(operands[0]) < _STACKED_BELOW:  # many small operands: a loop would cost more
        return new_conjunction(np.stack(np.broadcast_arrays(*operands), axis=-1), nu)
    shape = np.broadcast_shapes(*(np.shape(operand) for operand in operands))
    size = math.prod(shape)
    if size <= _CACHED_OPERAND_ELEMENTS:
        return _conjunction_of(operands, nu)
    flat = [np.broadcast_to(operand, shape).reshape(-1) for operand in operands]
    result = np.empty(size)
    for begin in range(0, size, _CACHED_OPERAND_ELEMENTS):
        chunk = slice(begin, begin + _CACHED_OPERAND_ELEMENTS)
        result[chunk] = _conjunction_of([operand[chunk] for operand in flat], nu)
    return result.reshape(shape)


# Elements of each operand that `new_conjunction_of` takes at once: its operands and
# temporaries stay in cache (measured: 3 operands of 128 x 2,200, 12.5 ms whole, 4.9 ms so).
_CACHED_OPERAND_ELEMENTS = 1 << 13


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


def window_min(values: np.ndarray, width: int, count: int) -> np.ndarray:
    """Forward sliding minimum: `out[..., i] = min(values[..., i : i + width])`.

    Windows past the end are clipped; a window with no sample gives +inf. Cost O(n) whatever
    the width: van Herk / Gil-Werman, the minimum of a block suffix and the next block's prefix.

    Args:
        values: `... x n` array.
        width: window length in samples, >= 1.
        count: number of outputs.

    Returns:
        `... x count` array.
    """
    values = _pad(values, count, np.inf)
    if count == 1:
        return values[..., :width].min(axis=-1, keepdims=True)
    if width >= values.shape[-1]:
        return suffix_min(values)[..., :count]
    blocks = -(-(count + width - 1) // width)
    padded = _pad(values, blocks * width, np.inf)[..., : blocks * width]
    shaped = padded.reshape(padded.shape[:-1] + (blocks, width))
    prefix = np.minimum.accumulate(shaped, axis=-1).reshape(padded.shape)
    suffix = np.minimum.accumulate(shaped[..., ::-1], axis=-1)[..., ::-1].reshape(padded.shape)
    return np.minimum(suffix[..., :count], prefix[..., width - 1 : width - 1 + count])


def suffix_min(values: np.ndarray) -> np.ndarray:
    """`out[..., i] = min(values[..., i:])`."""
    return np.minimum.accumulate(values[..., ::-1], axis=-1)[..., ::-1]


def window_reduce(values: np.ndarray, width: int, count: int, reduce, nu: float) -> np.ndarray:
    """Forward sliding n-ary reduction `reduce(values[..., i : i + width], nu)`, O(count x width).

    Windows past the end are padded with +inf, the identity of a conjunction.

    Args:
        values: `... x n` array.
        width: window length in samples.
        count: number of outputs.
        reduce: a conjunction such as `new_conjunction`.

    Returns:
        `... x count` array.
    """
    if reduce is new_conjunction and width >= _INTERPOLATED_WIDTH_MIN and count > 1:
        return _interpolated_windows(values, width, count, nu)
    values = _pad(values, count + width - 1, np.inf)
    windows = sliding_window_view(values, width, axis=-1)  # ... x (n - width + 1) x width
    batch = int(np.prod(values.shape[:-1], dtype=int))
    step = max(1, _CHUNK_ELEMENTS // max(1, batch * width))
    parts = [reduce(windows[..., begin : min(begin + step, count), :], nu) for begin in range(0, count, step)]
    return np.concatenate(parts, axis=-1)


def until_windows(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int, conjunction, nu: float) -> np.ndarray:
    """`left U[lo, width-1] right` at each of `count` outputs.

    For output i: the disjunction over j in [lo, width-1] of the conjunction of right[i + j]
    and left[i], ..., left[i + j - 1]. Samples past the end do not count.

    Args:
        left, right: `... x n` arrays aligned on the same samples, output i at sample i.
        lo: first window offset in samples.
        width: window length in samples (offsets 0 .. width-1).
        count: number of outputs.
        conjunction: `classic_conjunction` or `new_conjunction`.

    Returns:
        `... x count` array.
    """
    if conjunction is not classic_conjunction:
        return _new_until(np.asarray(left, dtype=float), np.asarray(right, dtype=float), lo, width, count, nu)
    length = count + width - 1
    left_windows = sliding_window_view(_pad(left, length, np.inf), width, axis=-1)
    right_windows = sliding_window_view(_pad(right, length, -np.inf), width, axis=-1)
    batch = int(np.prod(left.shape[:-1], dtype=int))
    step = max(1, _CHUNK_ELEMENTS // max(1, batch * width))
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


# --- Until under the new robustness ---------------------------------------------------------
#
# Candidate (i, j) of `left U right` is the new conjunction of left[i .. i+j-1] and right[i+j].
# With m its minimum and x_k = (v_k - m) / |m| >= 0 it is m N / D (m < 0) or N / D (m > 0),
# D = sum_k exp(-nu x_k) and N = sum_k exp(-(1 + nu) x_k) (m < 0) or sum_k v_k exp(-nu x_k)
# (m > 0): sums of positive terms of at most 1 (times v_k), so nothing overflows. Every term
# depends on m through 1/m, so no sum carries over from one minimum to another: there is no
# exact recursion over a growing window. But m is always one operand, the candidate's owner:
# right[i+j] when it is below the prefix, else the first minimum q of the prefix. Each owner
# sums its terms once, outward from itself, for every candidate it owns:
# - right[i+j] sums left[i .. i+j-1] backwards: per output i a band of running sums over the
#   chunk's outputs (samples < count) plus one total over the samples from count on;
# - q does the same over left[i .. q-1], and keeps running sums forwards over left[q ..],
#   shared by the owners of a flat stretch of equal minima.
# The work is the owners' reach, at most (count + width) x width terms, where the matrix of
# every candidate's operands cost count x width^2. A single output whose right operand stays
# below left still needs its own sum for every j: width^2 / 2 terms, inherent to the formula.
# The totals, the bulk of that case, are taken in cache-sized blocks of owners x samples.
# A single output (a top-level until) has its own kernel, `_first_output_candidates`: all its
# sums start at sample 0, so that every owner's is one tail sum, taken in one call.

# Elements of one block of owners x samples: small enough to stay in cache.
_BLOCK_ELEMENTS = 1 << 16
# Up to this nu, exp(-nu x_k) is exp(-nu v_k / |m|) times a constant of the owner (one multiply
# a term instead of three); above it the constant would leave the floating-point range.
_FACTORED_NU_MAX = 20.0


def _new_until(left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int, nu: float) -> np.ndarray:
    """`until_windows` under the new robustness: `... x n` operands -> `... x count`."""
    shape = left.shape[:-1]
    if lo >= width:
        return np.full(shape + (count,), -np.inf)
    length = count + width - 1
    left = _pad(left, length, np.inf)[..., :length].reshape(-1, length)
    right = _pad(right, length, -np.inf)[..., :length].reshape(-1, length)
    if count == 1:  # a top-level until: the first sample only
        with np.errstate(all="ignore"):
            return _disjunction(_first_output_candidates(left, right, lo, nu), nu).reshape(shape + (1,))
    step = max(1, _CHUNK_ELEMENTS // (4 * left.shape[0] * width))
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


@dataclass(frozen=True)
class _Runs:
    """Running sums of weights and numerators, one run per owner: the sums of its first t terms
    (t >= 1) are `sums[:, offsets[owner] + t - 1]` times `factors[:, owner]`."""

    sums: np.ndarray  # 2 x total
    offsets: np.ndarray  # owners
    factors: np.ndarray  # 2 x owners


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


def _cumulative_sums(values: np.ndarray, rows: np.ndarray, starts: np.ndarray, lengths: np.ndarray, scales: np.ndarray, nu: float) -> _Runs:
    """Running sums of the terms of values[row, start], values[row, start + 1], ... for
    `length` samples, one run per owner (rows, starts, lengths, scales: owners).

    Runs are taken by length in blocks of owners x samples, padded to the block's longest;
    samples past a run are read but never summed into it, so they may be anything.
    """
    order = np.argsort(lengths, kind="stable")
    order = order[lengths[order] > 0]
    blocks = _blocks(lengths[order], _BLOCK_ELEMENTS)
    spans = np.array([int(lengths[order[block][-1]]) for block in blocks], dtype=np.int64)
    sizes = np.array([block.stop - block.start for block in blocks], dtype=np.int64) * spans
    sums = np.empty((2, int(sizes.sum())))
    offsets = np.zeros(lengths.size, dtype=np.int64)
    factors = np.ones((2, lengths.size))
    if order.size == 0:
        return _Runs(sums, offsets, factors)
    windows = sliding_window_view(_pad(values, values.shape[-1] + int(spans[-1]), np.inf), int(spans[-1]), axis=-1)
    factored = nu <= _FACTORED_NU_MAX and np.all(np.isfinite((1 + nu) / np.abs(scales)))
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


def _factored_constants(scales: np.ndarray, nu: float) -> np.ndarray:
    """`2 x k`: the constants `_factored_terms`' weights and numerators are multiplied by to be
    `_terms`' (-nu x = -nu v / |m| -+ nu, and -(1 + nu) x for a negative numerator)."""
    negative = scales < 0
    return np.exp(np.stack([np.where(negative, -nu, nu), np.where(negative, -(1 + nu), nu)]))


def _factored_terms(values: np.ndarray, scales: np.ndarray, nu: float, out: np.ndarray) -> None:
    """`_terms` of `k x n` operands under `k` scales, each row divided by a constant: weights
    exp(-nu v / |m|) and numerators exp(-(1 + nu) v / |m|) (m < 0) or v exp(-nu v / |m|) (m > 0),
    into `out` (`2 x k x n`). Needs nu <= _FACTORED_NU_MAX and (1 + nu) / |m| finite."""
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


def _tail_sums(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """`2 x owners` sums of the terms of left[row, start .. end-1] under each owner's scale
    (0 where end <= start). Every sample summed is above its owner's scale.

    Owners that sum many samples take them by interpolation where it is exact to rounding
    (`_interpolated_tail_sums`), the others term by term.
    """
    lengths = ends - start
    long = np.flatnonzero(lengths >= 4 * _POINT_COUNTS[0])
    # interpolation costs at least the fewest points times the longest sum
    if long.size == 0 or lengths[long].sum() < _POINT_COUNTS[0] * _INTERPOLATION_COST * lengths.max():
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
        for block in _blocks(ends[group] - start, _BLOCK_ELEMENTS):
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
    if nu > _FACTORED_NU_MAX or not np.all(np.isfinite((1 + nu) / magnitudes)):
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


# --- Long sums by interpolation ---------------------------------------------------------------
#
# The tail sums of one row's owners all sum the same samples v_k, each owner m its own function
# f(v) = exp(-a (v - m)) (a = nu / |m| for weights, (1 + nu) / |m| for the numerators of a
# negative m; v exp(-a (v - m)) for those of a positive one). Interpolated at R Chebyshev
# points t_r of the row's range [lo, hi], f(v) = sum_r f(t_r) l_r(v) with the Lagrange basis
# l_r, so that sum_{k < e} f(v_k) = sum_r f(t_r) L_r(e) with L_r(e) = sum_{k < e} l_r(v_k):
# running sums of the basis, once per row, and R terms per owner instead of e. At Chebyshev
# points the error is at most 2 ((hi - lo) / 4)^R max |f^(R)| / R! per sample, where
# max |f^(R)| = a^R exp(a (m - lo)) (times (R / a + max |v|) for v exp(..)): an owner takes the
# interpolation when, for each of its two sums at its own rate, its samples' errors add up to
# at most _INTERPOLATION_ERROR next to its own term (1, or m for a positive numerator), and
# when f stays within e^2 at the nodes (rounding); the others sum term by term. A row takes
# it only where it costs less.
# Bounded windows under the new robustness (`_interpolated_windows`) do the same with the
# windows' minima as owners: a window's sums are differences of two running sums.
#
# Numbers of points R an owner may take (the fewest that are exact enough), and its row with it.
_POINT_COUNTS = (12, 16, 20, 24, 32, 40, 48)
_INTERPOLATION_ERROR = 1e-14
_LOG_FACTORIALS = np.array([math.lgamma(count + 1) for count in _POINT_COUNTS])
# Largest log f(t_r) an owner's node values may reach: the interpolation's rounding grows with
# them (f is at most 1 on the owner's own samples, larger below its scale).
_NODE_VALUE_LOG_MAX = 2.0
# Cost of one node at one sample or one owner, in terms summed one by one (measured).
_INTERPOLATION_COST = 4
# Running sums are taken within blocks of this many samples, as one product with a lower
# triangular matrix of ones (several times faster than cumsum, measured), then across blocks.
_RUNNING_BLOCK = 16
_LOWER_ONES = np.tril(np.ones((_RUNNING_BLOCK, _RUNNING_BLOCK)))
# Elements of the running sums of one chunk of rows: small enough to stay in cache with their
# owners' terms (measured: larger chunks, memory-bound, took twice as long).
_CACHED_ELEMENTS = 1 << 17


def _interpolated_tail_sums(left: np.ndarray, rows: np.ndarray, start: int, ends: np.ndarray, scales: np.ndarray, nu: float) -> tuple[np.ndarray, np.ndarray]:
    """`_tail_sums` by interpolation where it is within `_INTERPOLATION_ERROR`: the sums
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
    points, taken = _points_taken(row_index, lows, highs, ends - start, stops - start, scales, nu, _INTERPOLATION_COST)
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
    number of points, in chunks whose running sums stay within `_CACHED_ELEMENTS`.

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
        step = max(1, _CACHED_ELEMENTS // (count * values.shape[-1]))
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
    counts = np.array(_POINT_COUNTS)
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
    """The fewest of `_POINT_COUNTS` points at which interpolating each owner's sums over [low,
    high] errs by at most `_INTERPOLATION_ERROR` over its `counts` samples, next to its own term
    (bound above, in logarithms): the weights at rate nu / |m| and the numerators, at (1 + nu)
    / |m| for a negative m, v exp(-nu (v - m) / |m|) for a positive one (whose derivatives carry
    |v| + R / a, next to its own term m). 0 where none does, or where the node values would be
    too large."""
    magnitudes = np.abs(scales)
    negative = scales < 0
    weight_rates = nu / magnitudes
    numerator_rates = np.where(negative, (1 + nu) / magnitudes, weight_rates)
    too_many = _POINT_COUNTS[-1] + 1
    with np.errstate(all="ignore"):
        base = math.log(_INTERPOLATION_ERROR) - np.log(2 * np.maximum(counts, 1))
        peak = np.maximum(np.maximum(np.abs(lows), np.abs(highs)), magnitudes)
        numerator_scale = np.where(negative, 0.0, np.log((peak + _POINT_COUNTS[-1] / weight_rates) / magnitudes))
        needed = _fewest_points(numerator_rates, numerator_scale, lows, highs, scales, base)
        # Where m >= low the numerators' bound is the stricter (a rate at least the weights',
        # a scale at least 0): the weights' is checked only below the range.
        below = np.flatnonzero(scales < lows)
        if below.size:
            weights_needed = _fewest_points(weight_rates[below], 0.0, lows[below], highs[below], scales[below], base[below])
            needed[below] = np.maximum(needed[below], weights_needed)
        # the larger rate is the numerators': exp(a (m - low)) at the nodes within e^2
        values_bounded = (numerator_rates * (scales - lows) <= _NODE_VALUE_LOG_MAX) & (nu <= _FACTORED_NU_MAX)
    needed[(needed == too_many) | ~values_bounded | ~(highs > lows)] = 0
    np.copyto(needed, _POINT_COUNTS[0], where=(highs == lows) & values_bounded)  # one value: exact
    return needed


def _fewest_points(rates: np.ndarray, scale: np.ndarray | float, lows: np.ndarray, highs: np.ndarray, scales: np.ndarray, base: np.ndarray) -> np.ndarray:
    """The fewest of `_POINT_COUNTS` for which the bound of `_points_needed` holds for one sum
    at `rates` (its derivatives times exp(`scale`)), or one more than the most."""
    margin = base - rates * (scales - lows) - scale
    log_reach = np.log(rates * (highs - lows) / 4)
    fewest = np.full(scales.size, _POINT_COUNTS[-1] + 1)
    for count, log_factorial in zip(_POINT_COUNTS[::-1], _LOG_FACTORIALS[::-1]):  # a count at a time: fast on many owners
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
    blocks = -(-samples // _RUNNING_BLOCK)
    padded = np.zeros((blocks * _RUNNING_BLOCK, rows, count))
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
    running = np.empty((blocks * _RUNNING_BLOCK + 1, rows, count))
    running[0] = 0.0
    shaped = running[1:].reshape(blocks, _RUNNING_BLOCK, rows * count)
    np.matmul(_LOWER_ONES, padded.reshape(blocks, _RUNNING_BLOCK, rows * count), out=shaped)
    shaped[1:] += np.cumsum(shaped[:-1, -1], axis=0)[:, None]
    return running[: samples + 1]


def _node_sums(nodes: np.ndarray, counts: np.ndarray, scales: np.ndarray, nu: float) -> np.ndarray:
    """Weights and numerators (`2 x owners`) from each owner's terms at its row's nodes
    (`owners x R`) and the running basis sums there (`counts`, `owners x R`).

    The terms are taken factored (`_factored_terms`): the nodes are at most
    _NODE_VALUE_LOG_MAX below m and nu at most _FACTORED_NU_MAX, so nothing overflows.
    """
    terms = np.empty((2,) + nodes.shape)
    _factored_terms(nodes, scales, nu, out=terms)
    return np.einsum("wor,or->wo", terms, counts) * _factored_constants(scales, nu)


# Windows at least this wide take the interpolation where it is exact (see above): outputs are
# taken in groups of `width`, whose windows span 2 x width - 1 samples, a group's owners (the
# windows' minima) sharing the running sums of the basis over that span.
_INTERPOLATED_WIDTH_MIN = 64
# Cost of one node at one sample or one owner, in window operands (measured; a window's new
# conjunction costs more an operand than a tail sum a term).
_WINDOW_INTERPOLATION_COST = 1


def _interpolated_windows(values: np.ndarray, width: int, count: int, nu: float) -> np.ndarray:
    """`window_reduce(values, width, count, new_conjunction, nu)`: each window's weights and
    numerators, under its minimum, by interpolation over its group's span where that is exact,
    term by term elsewhere."""
    shape = values.shape[:-1]
    groups = -(-count // width)
    length = groups * width + width - 1
    padded = _pad(values, length, np.inf)[..., :length].reshape(-1, length)
    minima = window_min(padded, width, count)  # rows x count
    result = minima.copy()  # -inf, +inf and 0 are their own values
    row, output = np.nonzero(np.isfinite(minima) & (minima != 0))
    scales = minima[row, output]
    spans = sliding_window_view(padded, 2 * width - 1, axis=-1)[:, ::width].reshape(-1, 2 * width - 1)  # (rows x groups) x span
    lows, highs = _finite_range(spans)
    cell = row * groups + output // width
    points, taken = _points_taken(cell, lows, highs, np.full(row.size, width), np.full(spans.shape[0], spans.shape[1]), scales, nu, _WINDOW_INTERPOLATION_COST)
    owners = np.flatnonzero(taken)
    offsets = output[owners] % width
    numerators, weights = _interpolated_sums(spans, lows, highs, points, cell[owners], offsets, offsets + width, scales[owners], nu)[::-1]
    result[row[owners], output[owners]] = np.where(scales[owners] < 0, scales[owners] * numerators, numerators) / weights
    rest = np.flatnonzero(~taken)
    windows = sliding_window_view(padded, width, axis=-1)
    step = max(1, _CHUNK_ELEMENTS // width)
    for begin in range(0, rest.size, step):
        part = rest[begin : begin + step]
        result[row[part], output[part]] = new_conjunction(windows[row[part], output[part]], nu)
    return result.reshape(shape + (count,))


def _blocks(sizes: np.ndarray, budget: int) -> list[slice]:
    """Consecutive slices of `sizes` (non-decreasing) whose length times largest size stays
    within `budget` (at least one element a slice), and whose largest size is at most twice
    the smallest or `_PADDED_SIZE`: a slice padded to its largest wastes at most half of it,
    or pads short sizes to at most `_PADDED_SIZE`."""
    blocks, begin = [], 0
    while begin < sizes.size:
        most = max(1, budget // max(1, int(sizes[begin])))
        candidates = sizes[begin : begin + most]
        fits = (np.arange(1, candidates.size + 1) * np.maximum(candidates, 1) <= budget) & (candidates <= max(2 * int(sizes[begin]), _PADDED_SIZE))
        taken = candidates.size if fits.all() else max(1, int(np.argmin(fits)))
        blocks.append(slice(begin, begin + taken))
        begin += taken
    return blocks


# Sizes up to which `_blocks` pads freely (a block's calls cost more than its padding).
_PADDED_SIZE = 64


def _pad(values: np.ndarray, length: int, fill: float) -> np.ndarray:
    """`values` extended along the last axis to at least `length` with `fill`."""
    missing = length - values.shape[-1]
    if missing <= 0:
        return values
    padding = np.full(values.shape[:-1] + (missing,), fill)
    return np.concatenate([values, padding], axis=-1)
