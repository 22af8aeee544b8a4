"""Linear quadratic tracking by the backward Riccati recursion.

Minimises  sum_t (x_t - m_t)^T Q_t (x_t - m_t) + sum_t u_t^T R u_t  subject to
x_{t+1} = A x_t + B u_t and a given x_0. The value function is V_t(x) = x^T P_t x - 2 p_t^T x
+ const, with
    L_t = (R + B^T P_{t+1} B)^{-1},  K_t = L_t B^T P_{t+1} A,  k_t = L_t B^T p_{t+1},
    P_t = Q_t + A^T P_{t+1} (A - B K_t),  p_t = Q_t m_t + (A - B K_t)^T p_{t+1},
and the optimal control u_t = -K_t x_t + k_t.

Tracking targets are piecewise constant (one per HSMM state), so (P_t, p_t) reach the fixed
point of each segment's recursion after a few dozen steps; from there the step is skipped and
the converged values are reused, which makes the recursion cost scale with the number of
segments rather than the horizon. The P recursion of a segment does not depend on the targets,
so it is computed once for the segments that retrievals with other means or durations share.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

# Relative change below which the Riccati recursion counts as converged inside a segment
# (moves the retrieved trajectory by micrometres).
_CONVERGED = 1e-9


def double_integrator(dimension: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Discrete double integrator, state [position; velocity], control = acceleration.

    Returns:
        A: `2d x 2d`, B: `2d x d`.
    """
    identity = np.eye(dimension)
    zeros = np.zeros((dimension, dimension))
    A = np.block([[identity, dt * identity], [zeros, identity]])
    B = np.vstack([0.5 * dt**2 * identity, dt * identity])
    return A, B


def solve(
    A: np.ndarray,
    B: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray,
    targets: np.ndarray,
    x0: np.ndarray,
    segment_ids: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Optimal tracking trajectory.

    Args:
        A: `n x n` dynamics, B: `n x m` input matrix.
        Q: `T x n x n` state costs (or `S x n x n` with `segment_ids`).
        R: `m x m` control cost (positive definite).
        targets: `T x n` tracked states (or `S x n` with `segment_ids`).
        x0: `n` initial state.
        segment_ids: optional `T` integer array mapping each step to a row of `Q`/`targets`;
            consecutive equal ids form a segment whose converged recursion is reused.

    Returns:
        states: `T x n` trajectory (states[0] = x0), controls: `(T - 1) x m`.
    """
    steps = targets.shape[0] if segment_ids is None else segment_ids.size
    ids = np.arange(steps) if segment_ids is None else segment_ids
    gains, offsets = _backward(A, B, Q, R, targets, ids)
    states = np.empty((steps, A.shape[0]))
    controls = np.empty((steps - 1, B.shape[1]))
    states[0] = x0
    closed_loop = A - B @ gains  # (T-1) x n x n
    drive = np.einsum("nm,tm->tn", B, offsets)  # (T-1) x n
    for t in range(steps - 1):
        states[t + 1] = closed_loop[t] @ states[t] + drive[t]
    controls[:] = offsets - np.einsum("tmn,tn->tm", gains, states[:-1])
    return states, controls


@dataclass(frozen=True)
class _SegmentRecursion:
    """The Riccati recursion through one segment, from its end backwards: per step, the gain
    `K` (`m x n`), the map `L B^T` (`m x n`) from `p_{t+1}` to the feedforward term, the closed
    loop `A - B K` (`n x n`) and `P_t`; `converged` when the last step left P unchanged."""

    gains: tuple[np.ndarray, ...]
    feeds: tuple[np.ndarray, ...]
    closed: tuple[np.ndarray, ...]
    values: tuple[np.ndarray, ...]
    converged: bool


# The P recursion of a segment depends only on (A, B, R, its Q, the P it starts from), not on
# the targets; a skill retrieved again with other means or durations meets the same segments
# (its P at each segment's end is the next segment's converged value), so they are kept.
_RECURSIONS: OrderedDict[bytes, _SegmentRecursion] = OrderedDict()
_RECURSIONS_KEPT = 512


def _segment_recursion(A: np.ndarray, B: np.ndarray, R: np.ndarray, Q: np.ndarray, P: np.ndarray, length: int) -> _SegmentRecursion:
    """The recursion of a segment of `length` steps with state cost `Q`, entered with `P`:
    until P is unchanged or for `length` steps."""
    key = b"".join(np.ascontiguousarray(matrix).tobytes() for matrix in (A, B, R, Q, P))
    known = _RECURSIONS.get(key)
    if known is not None and (known.converged or len(known.gains) >= length):
        _RECURSIONS.move_to_end(key)
        return known
    n = A.shape[0]
    gains, feeds, closed_loops, values = [], [], [], []
    converged = False
    while len(gains) < length and not converged:
        PB = P @ B
        solution = np.linalg.solve(R + B.T @ PB, np.hstack([PB.T @ A, B.T]))  # m x 2n
        gain = solution[:, :n]
        closed = A - B @ gain
        P_next = Q + A.T @ P @ closed
        P_next = 0.5 * (P_next + P_next.T)  # rounding makes P drift from symmetry, then diverge
        converged = _unchanged(P_next, P)
        gains.append(gain)
        feeds.append(solution[:, n:])
        closed_loops.append(closed)
        values.append(P_next)
        P = P_next
    recursion = _SegmentRecursion(tuple(gains), tuple(feeds), tuple(closed_loops), tuple(values), converged)
    _RECURSIONS[key] = recursion
    if len(_RECURSIONS) > _RECURSIONS_KEPT:
        _RECURSIONS.popitem(last=False)
    return recursion


def _backward(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray, targets: np.ndarray, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Feedback gains `(T-1) x m x n` and feedforward terms `(T-1) x m`."""
    steps = ids.size
    n, m = B.shape
    gains = np.empty((steps - 1, m, n))
    offsets = np.empty((steps - 1, m))
    P = Q[ids[-1]].copy()
    p = Q[ids[-1]] @ targets[ids[-1]]
    t = steps - 2
    while t >= 0:
        segment = ids[t]
        Q_t, q_t = Q[segment], Q[segment] @ targets[segment]
        first = t
        while first > 0 and ids[first - 1] == segment:
            first -= 1
        recursion = _segment_recursion(A, B, R, Q_t, P, t - first + 1)
        last = len(recursion.gains) - 1
        for k in range(t - first + 1):
            step = min(k, last)
            gains[t], offsets[t] = recursion.gains[step], recursion.feeds[step] @ p
            p_next = q_t + recursion.closed[step].T @ p
            steady = recursion.converged and k >= last and _unchanged(p_next, p)
            p = p_next
            t -= 1
            if steady and t >= first:
                # Fixed point reached: every earlier step of the segment is the same.
                gains[first : t + 1] = gains[t + 1]
                offsets[first : t + 1] = offsets[t + 1]
                t = first - 1
                break
        P = recursion.values[min(k, last)]
    return gains, offsets


def _unchanged(new: np.ndarray, old: np.ndarray) -> bool:
    return float(np.max(np.abs(new - old))) <= _CONVERGED * (1.0 + float(np.max(np.abs(old))))
