"""Numerical kernels of the robustness semantics: n-ary conjunctions and sliding windows.

All functions take and return float arrays; reductions run along the last axis. Infinite
operands stand for empty windows: +inf is the identity of a conjunction, -inf of a disjunction.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

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
    safe_values = np.where(finite, values, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        relative = (safe_values - safe_minimum) / safe_minimum  # ... x m
        # Negative branch: relative <= 0 for every finite operand, +inf operands drop out.
        negative_weights = np.where(finite, np.exp(nu * relative), 0.0)
        negative = safe_minimum[..., 0] * np.sum(negative_weights * np.exp(relative), axis=-1) / np.sum(negative_weights, axis=-1)
        # Positive branch: relative >= 0.
        positive_weights = np.where(finite, np.exp(-nu * relative), 0.0)
        positive = np.sum(safe_values * positive_weights, axis=-1) / np.sum(positive_weights, axis=-1)
    minimum = minimum[..., 0]
    result = np.where(minimum > 0, positive, np.where(minimum < 0, negative, 0.0))
    return np.where(np.isfinite(minimum), result, minimum)


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
    length = count + width - 1
    left_windows = sliding_window_view(_pad(left, length, np.inf), width, axis=-1)
    right_windows = sliding_window_view(_pad(right, length, -np.inf), width, axis=-1)
    batch = int(np.prod(left.shape[:-1], dtype=int))
    classic = conjunction is classic_conjunction
    cost = width if classic else width * width
    step = max(1, _CHUNK_ELEMENTS // max(1, batch * cost))
    parts = []
    for begin in range(0, count, step):
        chunk = slice(begin, min(begin + step, count))
        lefts, rights = left_windows[..., chunk, :], right_windows[..., chunk, :]  # ... x c x width
        if classic:
            before = np.minimum.accumulate(lefts, axis=-1)
            before = np.concatenate([np.full_like(before[..., :1], np.inf), before[..., :-1]], axis=-1)
            candidates = np.minimum(rights, before)
        else:
            candidates = conjunction(_until_operands(lefts, rights), nu)  # ... x c x width
        candidates[..., :lo] = -np.inf
        parts.append(candidates.max(axis=-1) if classic else new_disjunction(candidates, nu))
    return np.concatenate(parts, axis=-1)


def _until_operands(lefts: np.ndarray, rights: np.ndarray) -> np.ndarray:
    """`... x width x width` operands: row j holds left[0..j-1], right[j], then +inf."""
    width = lefts.shape[-1]
    rows = np.arange(width)[:, None]
    columns = np.arange(width)[None, :]
    operands = np.where(columns < rows, lefts[..., None, :], np.inf)
    diagonal = np.broadcast_to(rights[..., :, None], operands.shape[:-1] + (1,))
    np.copyto(operands, np.broadcast_to(diagonal, operands.shape), where=columns == rows)
    return operands


def _pad(values: np.ndarray, length: int, fill: float) -> np.ndarray:
    """`values` extended along the last axis to at least `length` with `fill`."""
    missing = length - values.shape[-1]
    if missing <= 0:
        return values
    padding = np.full(values.shape[:-1] + (missing,), fill)
    return np.concatenate([values, padding], axis=-1)
