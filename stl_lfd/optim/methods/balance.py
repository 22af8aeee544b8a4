"""The spec's parts on one scale for the search, whatever units their predicates are written in.

A spec mixes quantities: `F[8, 12] (|x - 0.6| < 0.01) & G force < 5` compares metres and
newtons. Composed as they are, a force 20 N over its bound outweighs a position 15 mm off by
2,000 to 1, and the search sees only the force until it holds. Methods `stl` and `plan` divide
each output (a part or a route, `Composition`) by its scale before composing: its spread over
the values seen so far (`output_scales`), so that a part that is 5 of its own spreads from
holding weighs as much as another 5 of its spreads away, and a predicate rewritten in
millimetres gives the same search. Dividing by a positive number keeps every sign, so a
composed value above 0 still means the spec holds: only the search changes, never the
verdict or the recorded robustness.
"""

from __future__ import annotations

import numpy as np

from stl_lfd.stl import Semantics

MAD_TO_STD = 1.4826  # the median absolute deviation of a normal distribution, in standard deviations
MIN_TRIALS = 3  # fewer trials do not show a spread: one trial's value is no scale of a part


def output_scales(values: np.ndarray) -> np.ndarray:
    """`n x o` values (rows: trials or candidate points; NaN: unknown) -> `o` positive scales.

    Per column: its median absolute deviation (as a standard deviation; robust to the one trial
    that pushed at 100 N), or where that is 0 its standard deviation, or its largest magnitude,
    or 1 for a column of zeros or of nothing known. Each is proportional to the column's units."""
    values = np.asarray(values, dtype=float)
    scales = np.ones(values.shape[1])
    for column in range(values.shape[1]):
        known = values[np.isfinite(values[:, column]), column]
        if not len(known):
            continue
        spreads = (MAD_TO_STD * np.median(np.abs(known - np.median(known))), np.std(known), np.max(np.abs(known)))
        scales[column] = next((spread for spread in spreads if spread > 0), 1.0)
    return scales


def balanced_values(outputs: np.ndarray, scales: np.ndarray, parts: int, route_parts: tuple[int, ...], semantics: Semantics, groups: int = 1) -> np.ndarray:
    """`n x (m + r)` observed outputs -> `n` composed values, each output divided by its scale
    first and each part raised to its routes' (as the acquisition composes its samples)."""
    import torch

    from stl_lfd.optim.methods.composition import compose, through_routes  # torch: loaded once a model proposes

    samples = through_routes(torch.as_tensor(np.asarray(outputs, dtype=float) / scales), parts, route_parts)
    return compose(samples, semantics, groups).numpy()
