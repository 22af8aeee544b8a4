"""Trajectory retrieval: HSMM state sequence, then linear quadratic tracking of the state means.

The state sequence and the tracker run at the model's sample period; the result is resampled
to the requested rate by cubic Hermite interpolation of positions and velocities, which is
exact to well below a millimetre for these smooth trajectories and keeps retrieval cheap at
execution rates such as 240 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm import lqt
from stl_lfd.hsmm.io import load_model
from stl_lfd.hsmm.learn import frame_poses
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.tp import TPHSMM
from stl_lfd.limits import samples_problem
from stl_lfd.poses import Pose
from stl_lfd.rotations import QUATERNION_COLUMNS, ROTATION_COLUMNS
from stl_lfd.signals import SignalTable

# Control cost of the tracker relative to the state precisions; smaller tracks the means
# more tightly, larger gives smoother, lazier motion.
DEFAULT_CONTROL_COST = 1e-5


@dataclass
class Trajectory:
    """A retrieved reference.

    Attributes:
        times: `T` seconds from 0.
        positions: `T x D` in the model's signals (metres for x, y, z).
        velocities: `T x D`.
        states: `T` HSMM state followed at each sample.
        signal_names: the D names.
        orientations: `T x 4` quaternions (x, y, z, w) of a skill with orientation (its
            `rx, ry, rz` columns, relative to the model's reference); None without.
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    states: np.ndarray
    signal_names: list[str]
    orientations: np.ndarray | None = None

    def signal_table(self) -> SignalTable:
        """The trajectory as a signal table: the model's signals (the orientation as `qx, qy,
        qz, qw`, not its `rx, ry, rz` columns) and `state`, the state followed (1-based)."""
        columns = {name: self.positions[:, index] for index, name in enumerate(self.signal_names) if name not in ROTATION_COLUMNS}
        if self.orientations is not None:
            columns.update(zip(QUATERNION_COLUMNS, self.orientations.T))
        columns["state"] = self.states + 1.0
        return SignalTable(self.times, columns)


def retrieve(
    model: HSMM,
    duration: float | None = None,
    rate: float | None = None,
    control_cost: float = DEFAULT_CONTROL_COST,
    poses: Mapping[str, Pose] | None = None,
) -> Trajectory:
    """Reference trajectory of `model`.

    Args:
        model: a fitted (possibly modified) HSMM or TP-HSMM.
        duration: seconds to retrieve (default: the model's expected duration, to the nearest
            multiple of its sample period).
        rate: samples per second of the result (default: the model's own rate).
        control_cost: weight r of the acceleration cost R = r I.
        poses: for a TP-HSMM, the pose of every frame but `base` (see `TPHSMM.at`).

    Returns:
        The trajectory (base frame), starting at rest at the mean of the first state. A skill
        with orientation is tracked in the tangent space of its reference orientation (each
        state's covariance transported there) and mapped back to quaternions, so the
        orientation is continuous and reaches each state's mean orientation as the position
        reaches its mean (Calinon, IEEE RAM 2020).
    """
    return retrieve_batch([model], [duration], rate, control_cost, poses)[0]


def retrieve_file(path: str | Path, duration: float | None = None, rate: float | None = None, frames: Sequence[str] = ()) -> Trajectory:
    """`retrieve` of the model in the file `path`, a TP-HSMM for the frame poses `frames`
    (`NAME=x,y,z[,yaw]` texts, one per frame of the model but `base`: `frame_poses`).

    Raises:
        ModelError: naming the file (and the expected duration, when `duration` is not given)
            when the model cannot be retrieved.
    """
    model = load_model(path)
    poses = frame_poses(model, list(frames), path)
    try:
        return retrieve(model, duration, rate, poses=poses)
    except ModelError as error:
        whose = "" if duration is not None else f" (its expected duration, {model.expected_duration():.3g} s)"
        raise ModelError(f"{path}{whose}: {error}") from None


def retrieve_batch(
    models: Sequence[HSMM],
    durations: Sequence[float | None] | None = None,
    rate: float | None = None,
    control_cost: float = DEFAULT_CONTROL_COST,
    poses: Mapping[str, Pose] | None = None,
) -> list[Trajectory]:
    """The reference trajectories of N models (`retrieve` of each, exactly), their trackers
    solved together (`lqt.solve_batch`) where the models share a sample period and signals: the
    same skill with other parameters, as method `plan` retrieves the plans of its candidates.

    Args:
        models: N fitted HSMMs or TP-HSMMs.
        durations: N seconds to retrieve (None, or a None entry: as `retrieve`'s default).
        rate: samples per second of the results (default: the models' own rate).
        control_cost: weight r of the acceleration cost R = r I.
        poses: for TP-HSMMs, the pose of every frame but `base` (see `TPHSMM.at`).
    """
    durations = [None] * len(models) if durations is None else list(durations)
    models = [model.at(poses or {}) if isinstance(model, TPHSMM) else model for model in models]
    trajectories: list[Trajectory | None] = [None] * len(models)
    for (dt, dimension, _), members in _grouped(models, lambda model: (model.sample_period_, model.n_features, tuple(model.signal_names_))).items():
        problems = [_tracking(models[i], durations[i], rate, control_cost) for i in members]
        A, B = lqt.double_integrator(dimension, dt)
        solutions = lqt.solve_batch(A, B, [problem for problem, _, _ in problems])
        # Retrievals of the same length and duration are resampled together.
        for (_, duration), same in _grouped(problems, lambda problem: (problem[1].size, problem[2])).items():
            states, solution = np.stack([problems[k][1] for k in same]), np.stack([solutions[k] for k in same])
            for k, trajectory in zip(same, _trajectories(models[members[same[0]]], states, solution, duration, rate)):
                trajectory.orientations = models[members[k]].orientations(trajectory.positions)
                trajectories[members[k]] = trajectory
    return trajectories


def _grouped(items: Sequence, key: Callable) -> dict:
    """The positions of `items` by `key(item)`, in order."""
    groups: dict = {}
    for index, item in enumerate(items):
        groups.setdefault(key(item), []).append(index)
    return groups


def _tracking(model: HSMM, duration: float | None, rate: float | None, control_cost: float) -> tuple[lqt.Tracking, np.ndarray, float]:
    """The tracking problem of retrieving `model` for `duration` seconds (None: its expected
    duration) at `rate`, its `T` state sequence and the duration."""
    dt = model.sample_period_
    # By default the expected duration on the model's own time grid, so that the skill lasts as
    # long at every rate (retrieved at the model's rate, or executed at the simulation's).
    duration = dt * round(model.expected_duration() / dt) if duration is None else float(duration)
    problem = samples_problem(duration, 1.0 / dt) or (samples_problem(duration, float(rate)) if rate is not None else "")
    if problem:
        raise ModelError(f"cannot retrieve the skill: {problem}")
    steps = int(round(duration / dt)) + 1
    states = model.state_sequence(steps)
    dimension = model.n_features
    means, covars, segments = _tracked(model, states)
    precisions = np.zeros((len(means), 2 * dimension, 2 * dimension))
    precisions[:, :dimension, :dimension] = np.linalg.inv(covars)
    targets = np.zeros((len(means), 2 * dimension))
    targets[:, :dimension] = means
    scale = float(np.mean([np.trace(p) / dimension for p in precisions[: model.n_states, :dimension, :dimension]]))
    R = control_cost * scale * np.eye(dimension)
    x0 = targets[states[0]].copy()
    return lqt.Tracking(precisions, R, targets, x0, segments), states, duration


def _trajectories(model: HSMM, states: np.ndarray, solutions: np.ndarray, duration: float, rate: float | None) -> list[Trajectory]:
    """The retrieved trajectories (without orientations) of N retrievals of `model`'s skill
    from their `N x T` state sequences and the tracker's `N x T x 2D` solutions, at `rate`."""
    dt, dimension, names = model.sample_period_, model.n_features, list(model.signal_names_)
    times = np.arange(states.shape[1]) * dt
    positions, velocities = solutions[..., :dimension], solutions[..., dimension:]
    if rate is not None and not np.isclose(rate * dt, 1.0):
        new_times = np.arange(int(np.floor(duration * rate + 1e-9)) + 1) / rate
        # One spline of N x D columns: T x (N x D) in, S x (N x D) out.
        columns = [np.ascontiguousarray(values.transpose(1, 0, 2)).reshape(len(times), -1) for values in (positions, velocities)]
        positions, velocities = (
            values.reshape(len(new_times), len(states), dimension).transpose(1, 0, 2) for values in hermite_interpolation(times, *columns, new_times)
        )
        states = states[:, np.minimum(np.round(new_times / dt).astype(int), states.shape[1] - 1)]
        times = new_times
    return [Trajectory(times, positions[k], velocities[k], states[k], list(names)) for k in range(len(states))]


def _tracked(model: HSMM, states: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Gaussians the tracker follows (`S x D` means, `S x D x D` covariances) and the row
    followed at each step: the states' own, and in the second half of the final state (from
    half its duration mean on), the demonstrations' end point when the model knows it."""
    end = model.end_target()
    at_reference = model.coordinates().at_reference
    if end is None or states[-1] != end[0]:
        return np.asarray(model.means_), at_reference(model.means_, model.covars_), states
    before = np.flatnonzero(states != end[0])
    final_run = before[-1] + 1 if before.size else 0  # where the final state's run starts
    switch = final_run + max(1, int(round(model.duration_means_[end[0]] / model.sample_period_ / 2)))
    segments = states.copy()
    segments[switch:] = model.n_states
    means = np.vstack([model.means_, end[1]])
    return means, at_reference(means, np.concatenate([model.covars_, end[2][None]])), segments


def hermite_interpolation(times: np.ndarray, positions: np.ndarray, velocities: np.ndarray, new_times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities at `new_times` (`S`) of the cubic Hermite spline through
    `positions` and `velocities` (`T x D`) at increasing `times` (`T`), extrapolated by the end
    pieces.

    The same arithmetic, in the same order, as scipy's `CubicHermiteSpline` (the results are
    bit-identical, which a test checks): importing `scipy.interpolate` costs every command that
    retrieves a trajectory about 0.8 s. Many columns (a batch of plans) are taken a block at a
    time, whose temporaries stay in cache.
    """
    piece = np.clip(np.searchsorted(times, new_times, side="right") - 1, 0, len(times) - 2)
    offset = (new_times - times[piece])[:, None]
    new_positions, new_velocities = np.empty((len(new_times), positions.shape[1])), np.empty((len(new_times), positions.shape[1]))
    for start in range(0, positions.shape[1], _SPLINE_COLUMNS):
        block = slice(start, start + _SPLINE_COLUMNS)
        new_positions[:, block], new_velocities[:, block] = _hermite_block(times, positions[:, block], velocities[:, block], piece, offset)
    return new_positions, new_velocities


# Columns of one block of `hermite_interpolation` (a few times 10^5 elements at 100 Hz).
_SPLINE_COLUMNS = 64


def _hermite_block(times: np.ndarray, positions: np.ndarray, velocities: np.ndarray, piece: np.ndarray, offset: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`hermite_interpolation` of `T x d` columns at the new times' `S` pieces and `S x 1`
    offsets into them."""
    steps = np.diff(times)[:, None]
    slopes = np.diff(positions, axis=0) / steps
    curvature = (velocities[:-1] + velocities[1:] - 2 * slopes) / steps
    cubic, quadratic, linear = curvature / steps, (slopes - velocities[:-1]) / steps - curvature, velocities[:-1]
    squared = offset * offset
    linear, quadratic, cubic = linear[piece], quadratic[piece], cubic[piece]
    new_positions = positions[:-1][piece] + linear * offset + quadratic * squared + cubic * (squared * offset)
    new_velocities = linear + quadratic * offset * 2 + cubic * squared * 3
    return new_positions, new_velocities
