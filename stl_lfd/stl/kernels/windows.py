"""Sliding windows: the minimum (classic `G`/`F` windows) and any conjunction over windows, the new
one by interpolation when windows are long.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from stl_lfd.stl.kernels import budgets
from stl_lfd.stl.kernels.conjunction import new_conjunction
from stl_lfd.stl.kernels.interpolation import _finite_range, _interpolated_sums, _points_taken
from stl_lfd.stl.kernels.memory import _pad


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


def new_windows(values: np.ndarray, width: int, count: int, nu: float) -> np.ndarray:
    """Forward sliding new conjunction `new_conjunction(values[..., i : i + width], nu)`,
    O(count x width), by interpolation when windows are long.

    Windows past the end are padded with +inf, the identity of a conjunction.

    Args:
        values: `... x n` array.
        width: window length in samples.
        count: number of outputs.
        nu: sharpness, > 0.

    Returns:
        `... x count` array.
    """
    if width >= budgets.INTERPOLATED_WIDTH_MIN and count > 1:
        return _interpolated_windows(values, width, count, nu)
    values = _pad(values, count + width - 1, np.inf)
    windows = sliding_window_view(values, width, axis=-1)  # ... x (n - width + 1) x width
    batch = int(np.prod(values.shape[:-1], dtype=int))
    step = max(1, budgets.CHUNK_ELEMENTS // max(1, batch * width))
    parts = [new_conjunction(windows[..., begin : min(begin + step, count), :], nu) for begin in range(0, count, step)]
    return np.concatenate(parts, axis=-1)


def _interpolated_windows(values: np.ndarray, width: int, count: int, nu: float) -> np.ndarray:
    """`new_windows(values, width, count, nu)` by interpolation: each window's weights and
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
    points, taken = _points_taken(
        cell, lows, highs, np.full(row.size, width), np.full(spans.shape[0], spans.shape[1]), scales, nu, budgets.WINDOW_INTERPOLATION_COST
    )
    owners = np.flatnonzero(taken)
    offsets = output[owners] % width
    numerators, weights = _interpolated_sums(spans, lows, highs, points, cell[owners], offsets, offsets + width, scales[owners], nu)[::-1]
    result[row[owners], output[owners]] = np.where(scales[owners] < 0, scales[owners] * numerators, numerators) / weights
    rest = np.flatnonzero(~taken)
    windows = sliding_window_view(padded, width, axis=-1)
    step = max(1, budgets.CHUNK_ELEMENTS // width)
    for begin in range(0, rest.size, step):
        part = rest[begin : begin + step]
        result[row[part], output[part]] = new_conjunction(windows[row[part], output[part]], nu)
    return result.reshape(shape + (count,))
