"""How much a kernel materialises at once: chunks of a windowed evaluation, and padding."""

from __future__ import annotations

import numpy as np

from stl_lfd.stl.kernels import budgets


def _blocks(sizes: np.ndarray, budget: int) -> list[slice]:
    """Consecutive slices of `sizes` (non-decreasing) whose length times largest size stays
    within `budget` (at least one element a slice), and whose largest size is at most twice
    the smallest or `budgets.PADDED_SIZE`: a slice padded to its largest wastes at most half of it,
    or pads short sizes to at most `budgets.PADDED_SIZE`."""
    blocks, begin = [], 0
    while begin < sizes.size:
        most = max(1, budget // max(1, int(sizes[begin])))
        candidates = sizes[begin : begin + most]
        fits = (np.arange(1, candidates.size + 1) * np.maximum(candidates, 1) <= budget) & (candidates <= max(2 * int(sizes[begin]), budgets.PADDED_SIZE))
        taken = candidates.size if fits.all() else max(1, int(np.argmin(fits)))
        blocks.append(slice(begin, begin + taken))
        begin += taken
    return blocks


def _pad(values: np.ndarray, length: int, fill: float) -> np.ndarray:
    """`values` extended along the last axis to at least `length` with `fill`."""
    missing = length - values.shape[-1]
    if missing <= 0:
        return values
    padding = np.full(values.shape[:-1] + (missing,), fill)
    return np.concatenate([values, padding], axis=-1)
