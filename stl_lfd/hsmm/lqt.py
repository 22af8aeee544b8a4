"""Linear quadratic tracking by the backward Riccati recursion.

Minimises  sum_t (x_t - m_t)^T Q_t (x_t - m_t) + sum_t u_t^T R u_t  subject to
x_{t+1} = A x_t + B u_t and a given x_0. The value function is V_t(x) = x^T P_t x - 2 p_t^T x
+ const, with
    L_t = (R + B^T P_{t+1} B)^{-1},  K_t = L_t B^T P_{t+1} A,  k_t = L_t B^T p_{t+1},
    P_t = Q_t + A^T P_{t+1} (A - B K_t),  p_t = Q_t m_t + (A - B K_t)^T p_{t+1},
and the optimal control u_t = -K_t x_t + k_t.

Tracking targets are piecewise constant (one per HSMM state), so P_t reaches the fixed point
of each segment's recursion after a few dozen steps; from there the converged gains are reused,
which makes the Riccati cost scale with the number of segments rather than the horizon. The P
recursion of a segment does not depend on the targets, so it is computed once for the segments
that retrievals with other means or durations share. What does depend on the targets (p_t and
the trajectory) is linear and cheap per step, and `solve_batch` runs it for many problems at
once (method `plan` retrieves the plans of a batch of candidate points so).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Sequence

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
    """Optimal tracking trajectory: `solve_batch` of one problem.

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
    ids = np.arange(targets.shape[0]) if segment_ids is None else np.asarray(segment_ids)
    (states,) = solve_batch(A, B, [Tracking(Q, R, targets, x0, ids)])
    controls = (states[1:] - states[:-1] @ A.T) @ np.linalg.pinv(B).T  # x_{t+1} = A x_t + B u_t
    return states, controls


@dataclass(frozen=True)
class Tracking:
    """One tracking problem of a batch (see `solve`).

    Attributes:
        Q: `S x n x n` state cost of each row, R: `m x m` control cost.
        targets: `S x n` tracked state of each row, x0: `n` initial state.
        segment_ids: `T` row of each step (T >= 2).
    """

    Q: np.ndarray
    R: np.ndarray
    targets: np.ndarray
    x0: np.ndarray
    segment_ids: np.ndarray


def solve_batch(A: np.ndarray, B: np.ndarray, problems: Sequence[Tracking]) -> list[np.ndarray]:
    """Optimal trajectories (`T_i x n` each, starting at x0) of N tracking problems with the
    same dynamics, vectorised over the problems.

    Each problem's gains come from its segments' recursions (`_segment_recursions`, shared by
    the problems that meet the same segments); the feedforward recursion and the trajectory
    then run for all problems at once, a step at a time. Problems are aligned at their ends:
    before a shorter one starts, its rows hold x0. Each problem's arithmetic is the same in any
    batch, so a batch gives exactly what each of its problems gives alone.
    """
    table = _GainTable(A, B)
    steps = max(problem.segment_ids.size for problem in problems)
    rows, firsts = table.rows(problems, steps)  # N x (steps - 1) each
    weighted = np.stack([_weighted_targets(problem, steps) for problem in problems])  # N x steps x n
    feeds, closed, settled = table.arrays()
    offsets = _feedforward(feeds, closed, settled, rows, firsts, weighted)
    states = _trajectory(B, closed, rows, offsets, np.stack([problem.x0 for problem in problems]))
    return [states[i, steps - problem.segment_ids.size :] for i, problem in enumerate(problems)]


class _GainTable:
    """The recursion steps that the problems of a batch use, in one table of rows; row 0 holds
    the state (no gain, the identity as closed loop) for the steps before a shorter problem."""

    def __init__(self, A: np.ndarray, B: np.ndarray) -> None:
        self.A, self.B = A, B
        n, m = B.shape
        self.parts = [_SegmentRecursion(np.zeros((1, m, n)), np.zeros((1, m, n)), np.eye(n)[None], np.zeros((1, n, n)), False)]
        self.first: dict[int, int] = {id(self.parts[0]): 0}  # a recursion's first row
        self.size = 1

    def rows(self, problems: Sequence[Tracking], steps: int) -> tuple[np.ndarray, np.ndarray]:
        """The table row of each of the problems' steps but the last, and the first step of
        the segment each is in, aligned at the end of `steps` (`N x (steps - 1)` each; row 0
        and first step 0 before a problem starts).

        Each problem's segments are walked backwards, each entered with the P its successor
        ends with: all problems' last segments first, then the ones before them, so that the
        recursions none has met yet are computed together (`_segment_recursions`).
        """
        rows, firsts = np.zeros((len(problems), steps - 1), dtype=np.intp), np.zeros((len(problems), steps - 1), dtype=np.intp)
        ends = {index: problem.segment_ids.size - 2 for index, problem in enumerate(problems)}  # the next step to walk
        segment_starts = [_segment_starts(problem.segment_ids) for problem in problems]
        entering = {index: problem.Q[problem.segment_ids[-1]] for index, problem in enumerate(problems)}
        while ends := {index: t for index, t in ends.items() if t >= 0}:
            starts = {index: int(segment_starts[index][t]) for index, t in ends.items()}
            requests = [
                (problems[index].R, problems[index].Q[problems[index].segment_ids[t]], entering[index], t - starts[index] + 1) for index, t in ends.items()
            ]
            for (index, t), recursion in zip(ends.items(), _segment_recursions(self.A, self.B, requests)):
                first, offset = starts[index], steps - problems[index].segment_ids.size
                last = len(recursion.gains) - 1
                rows[index, offset + first : offset + t + 1] = self._first_row(recursion) + np.minimum(np.arange(t - first, -1, -1), last)
                firsts[index, offset + first : offset + t + 1] = offset + first
                entering[index] = recursion.values[min(t - first, last)]
                ends[index] = first - 1
        return rows, firsts

    def _first_row(self, recursion: "_SegmentRecursion") -> int:
        if id(recursion) not in self.first:
            self.first[id(recursion)] = self.size
            self.parts.append(recursion)
            self.size += len(recursion.gains)
        return self.first[id(recursion)]

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Feedforward maps `G x m x n`, closed loops `G x n x n`, and `G` flags: the row is the
        fixed point of a converged recursion."""
        settled = [np.arange(len(part.gains)) == (len(part.gains) - 1 if part.converged else -1) for part in self.parts]
        return np.concatenate([part.feeds for part in self.parts]), np.concatenate([part.closed for part in self.parts]), np.concatenate(settled)


def _weighted_targets(problem: Tracking, steps: int) -> np.ndarray:
    """`steps x n`: Q_t m_t at each of the problem's steps, aligned at the end (0 before)."""
    weighted = np.zeros((steps, problem.Q.shape[-1]))
    weighted[steps - problem.segment_ids.size :] = (problem.Q @ problem.targets[:, :, None])[problem.segment_ids, :, 0]
    return weighted


def _feedforward(feeds: np.ndarray, closed: np.ndarray, settled: np.ndarray, rows: np.ndarray, firsts: np.ndarray, weighted: np.ndarray) -> np.ndarray:
    """Feedforward terms k_t (`N x (T-1) x m`) of the backward recursion p_t = Q_t m_t +
    (A - B K_t)^T p_{t+1} from p_{T-1} = Q_{T-1} m_{T-1}, for table `rows` (`N x (T-1)`),
    the first step of each step's segment (`firsts`) and the `weighted` targets (`N x T x n`).

    Once a problem's p stops changing at the fixed point of its segment's gains, p and k_t
    stay as they are to the segment's first step; while every problem is so, the steps are
    skipped to the nearest segment start.
    """
    count, steps = rows.shape
    offsets = np.empty((count, steps, feeds.shape[1], 1))
    weighted = weighted[..., None]  # N x T x n x 1
    transposed = closed.transpose(0, 2, 1)
    at_fixed_point, opens = settled[rows], firsts == np.arange(steps)  # N x (T-1) each
    checked, opened = at_fixed_point.any(axis=0).tolist(), opens.any(axis=0).tolist()  # per step, as Python flags
    p = weighted[:, -1]  # N x n x 1
    held = np.zeros(count, dtype=bool)  # p at its segment's fixed point
    held_any = held_all = False
    kept = held[:, None, None]  # `held` as a mask of rows
    t = steps - 1
    for chunk in _chunks(steps, count * closed[0].size, backwards=True):
        chunk_feeds, chunk_transposed = feeds[rows[:, chunk]], transposed[rows[:, chunk]]  # N x L x . x .
        while t >= chunk.start:
            if held_all:
                begin = int(firsts[:, t].max())
                offsets[:, begin : t + 1] = offsets[:, t + 1, None]
                held = firsts[:, t] < begin
                held_any, held_all, kept = bool(held.any()), bool(held.all()), held[:, None, None]
                t = begin - 1
                continue
            k = t - chunk.start
            np.matmul(chunk_feeds[:, k], p, out=offsets[:, t])
            following = chunk_transposed[:, k] @ p
            following += weighted[:, t]
            if held_any:
                np.copyto(offsets[:, t], offsets[:, t + 1], where=kept)
                np.copyto(following, p, where=kept)
            if checked[t] and (arriving := at_fixed_point[:, t] & ~held).any():
                held |= arriving & _unchanged_rows(following, p)
            if opened[t]:
                held &= ~opens[:, t]
            if checked[t] or opened[t]:
                held_any, held_all, kept = bool(held.any()), bool(held.all()), held[:, None, None]
            p = following
            t -= 1
    return offsets[..., 0]


def _trajectory(B: np.ndarray, closed: np.ndarray, rows: np.ndarray, offsets: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """States `N x T x n` from `x0` (`N x n`) under x_{t+1} = (A - B K_t) x_t + B k_t."""
    count, steps = rows.shape
    states = np.empty((count, steps + 1, x0.shape[1], 1))
    states[:, 0, :, 0] = x0
    drive = B @ offsets[..., None]  # N x (T-1) x n x 1
    for chunk in _chunks(steps, count * closed[0].size):
        loops = closed[rows[:, chunk]]  # N x L x n x n
        for t in range(chunk.start, chunk.stop):
            x = np.matmul(loops[:, t - chunk.start], states[:, t], out=states[:, t + 1])
            x += drive[:, t]
    return states[..., 0]


def _chunks(steps: int, size: int, backwards: bool = False) -> list[range]:
    """Ranges of steps whose gathered matrices (`size` numbers a step) fit in about a
    megabyte, in order (or last first)."""
    length = max(1, (1 << 17) // size)
    chunks = [range(start, min(start + length, steps)) for start in range(0, steps, length)]
    return chunks[::-1] if backwards else chunks


@dataclass(frozen=True)
class _SegmentRecursion:
    """The Riccati recursion through one segment, from its end backwards: per step, the gain
    `K` (`m x n`), the map `L B^T` (`m x n`) from `p_{t+1}` to the feedforward term, the closed
    loop `A - B K` (`n x n`) and `P_t`; `converged` when the last step left P unchanged."""

    gains: np.ndarray  # L x m x n
    feeds: np.ndarray  # L x m x n
    closed: np.ndarray  # L x n x n
    values: np.ndarray  # L x n x n
    converged: bool


# The P recursion of a segment depends only on (A, B, R, its Q, the P it starts from), not on
# the targets; a skill retrieved again with other means or durations meets the same segments
# (its P at each segment's end is the next segment's converged value), so they are kept.
_RECURSIONS: OrderedDict[bytes, _SegmentRecursion] = OrderedDict()
_RECURSIONS_KEPT = 512


def _segment_recursions(A: np.ndarray, B: np.ndarray, requests: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, int]]) -> list[_SegmentRecursion]:
    """The recursion of each segment `(R, Q, P, length)` (state cost Q, entered with P): until
    P is unchanged or for `length` steps. The kept ones are reused; the others are computed
    together, a step at a time for all of them (each with the arithmetic it has alone)."""
    keys = [b"".join(np.ascontiguousarray(matrix).tobytes() for matrix in (A, B, R, Q, P)) for R, Q, P, _ in requests]
    needed: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray, int]] = {}
    for key, (R, Q, P, length) in zip(keys, requests):
        known = _RECURSIONS.get(key)
        if known is not None and (known.converged or len(known.gains) >= length):
            _RECURSIONS.move_to_end(key)
        elif key not in needed or needed[key][3] < length:
            needed[key] = (R, Q, P, length)
    if needed:
        for key, recursion in zip(needed, _recursions(A, B, list(needed.values()))):
            _RECURSIONS[key] = recursion
            if len(_RECURSIONS) > _RECURSIONS_KEPT:
                _RECURSIONS.popitem(last=False)
    return [_RECURSIONS[key] if key in _RECURSIONS else _recursions(A, B, [request])[0] for key, request in zip(keys, requests)]


def _recursions(A: np.ndarray, B: np.ndarray, requests: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, int]]) -> list[_SegmentRecursion]:
    """The Riccati recursions of K segments `(R, Q, P, length)`, stepped together until each
    one's P is unchanged or it has `length` steps."""
    n = A.shape[0]
    R, Q, P = (np.stack([request[k] for request in requests]) for k in range(3))  # K x . x .
    lengths = np.array([request[3] for request in requests])
    steps: list[list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]] = [[] for _ in requests]
    converged = np.zeros(len(requests), dtype=bool)
    active = np.arange(len(requests))
    right = np.empty((len(requests), B.shape[1], 2 * n))
    right[:, :, n:] = B.T
    while active.size:
        current = P[active]
        PB = current @ B
        right[active, :, :n] = PB.transpose(0, 2, 1) @ A
        solution = np.linalg.solve(R[active] + B.T @ PB, right[active])  # k x m x 2n
        gain = solution[:, :, :n]
        closed = A - B @ gain
        following = Q[active] + A.T @ current @ closed
        following = 0.5 * (following + following.transpose(0, 2, 1))  # rounding makes P drift from symmetry, then diverge
        converged[active] = _unchanged_rows(following, current)
        for position, index in enumerate(active):
            steps[index].append((gain[position], solution[position, :, n:], closed[position], following[position]))
        P[active] = following
        active = active[(np.array([len(steps[index]) for index in active]) < lengths[active]) & ~converged[active]]
    return [_SegmentRecursion(*(np.array(part) for part in zip(*taken)), bool(done)) for taken, done in zip(steps, converged)]


def _segment_starts(ids: np.ndarray) -> np.ndarray:
    """`T`: the first step of each step's segment (a run of equal `ids`)."""
    opens = np.ones(ids.size, dtype=bool)
    opens[1:] = ids[1:] != ids[:-1]
    return np.maximum.accumulate(np.where(opens, np.arange(ids.size), 0))


def _unchanged_rows(new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """Whether each of N rows (`N x ...` arrays) is unchanged: its largest change within
    _CONVERGED of its largest entry (plus 1)."""
    new, old = new.reshape(len(new), -1), old.reshape(len(old), -1)
    return np.abs(new - old).max(axis=1) <= _CONVERGED * (1.0 + np.abs(old).max(axis=1))
