"""TuRBO's trust region (Eriksson et al. 2019), replayed from the history: a box whose side
grows after successes and shrinks after failures, so that a resumed run proposes exactly the
points an uninterrupted one would. (TuRBO is a BoTorch tutorial, not a class.)"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TrustRegion:
    """TuRBO's box, as a side length in the unit cube around the incumbent.

    Attributes:
        initial, minimum, maximum: side at the start, restart threshold, and cap.
        success_tolerance, failure_tolerance: consecutive successes (failures) that double
            (halve) the side.
    """

    initial: float = 0.8
    minimum: float = 0.5**5
    maximum: float = 1.6
    success_tolerance: int = 2
    failure_tolerance: int = 3


def trust_region_length(Y: np.ndarray, initial: int, region: TrustRegion = TrustRegion()) -> float:
    """The side of the trust region after the trials of `Y` (`n` composed values in trial
    order, the first `initial` of them the space-filling design).

    A trial succeeds when it improves the best value so far by more than 1e-3 of the range
    seen; the side doubles after `success_tolerance` successes in a row, halves after
    `failure_tolerance` failures in a row, and starts again at `initial` when it falls below
    `minimum`."""
    length, successes, failures = region.initial, 0, 0
    best = float(np.max(Y[:initial])) if initial > 0 else -np.inf
    scale = float(np.ptp(Y)) if len(Y) > 1 else 1.0
    for value in Y[initial:]:
        if value > best + 1e-3 * max(scale, 1e-12):
            successes, failures = successes + 1, 0
        else:
            successes, failures = 0, failures + 1
        best = max(best, float(value))
        if successes == region.success_tolerance:
            length, successes = min(2 * length, region.maximum), 0
        elif failures == region.failure_tolerance:
            length, failures = length / 2, 0
        if length < region.minimum:
            length = region.initial
    return length


def trust_box(center: np.ndarray, length: float) -> np.ndarray:
    """`2 x d` box of side `length` around `center` in the unit cube, clipped to it."""
    return np.vstack([np.clip(center - length / 2, 0.0, 1.0), np.clip(center + length / 2, 0.0, 1.0)])
