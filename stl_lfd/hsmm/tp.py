"""Task-parameterised HSMM: skills that follow the objects they act on.

Each state has one Gaussian per frame (the robot base and the objects of the demonstrations),
learned from the demonstrations expressed in every frame, with shared transitions and
durations (Calinon 2016; Rozo et al. 2020). For new object poses, `TPHSMM.at` transforms each
frame's Gaussians to the base frame and multiplies them: the result is an ordinary `HSMM`,
which the state sequence and the tracker use as before.

Poses move the position signals `x, y, z` (rotated by the frame's orientation, a yaw or any
rotation, then translated) and the hand's orientation (`qx, qy, qz, qw`: expressed in each
frame, then as a rotation vector relative to that frame's mean orientation, see
`stl_lfd.hsmm.orientation`); other signals (a gripper opening) are the same in every frame.
With orientation, the frames' Gaussians on R^n x S^3 are multiplied in the tangent space at
the product's mean, found by Gauss-Newton iterations (Zeestraten et al., RA-L 2017).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ModelError
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.orientation import Coordinates, to_model_columns
from stl_lfd.hsmm.spread import MinimumSpread
from stl_lfd.poses import BASE_FRAME, Pose
from stl_lfd.rotations import QUATERNION_COLUMNS

POSITION_SIGNALS = ("x", "y", "z")
RELEVANCE = 10.0  # see `relevant_frames`


class TPHSMM(HSMM):
    """An HSMM whose states are Gaussians in P frames at once.

    Hyperparameters (besides those of `HSMM`):
        relevance: a state's Gaussian in a frame enters the product only when its position's
            geometric-mean variance is at most `relevance` times the smallest over the frames
            (None: every frame, the classic product). See `relevant_frames` for why.

    Learned attributes (besides those of `HSMM`):
        frame_names_: the P frames; `base` is the robot base frame, fixed at the origin.
        means_: `K x (P*D)`: each state's mean in frame 1, then in frame 2, ... (D signals each).
        covars_: `K x P*D x P*D`, block diagonal: the frames are independent given the state.
        signal_names_: the D signals (as in the demonstrations, base frame; with orientation,
            `rx, ry, rz` in place of `qx, qy, qz, qw`).
        orientation_reference_: with orientation, `P x 4`: each frame's mean orientation of the
            hand, which that frame's rotation vectors are relative to.
    """

    def __init__(
        self,
        n_states: int = 6,
        n_iter: int = 50,
        tol: float = 1e-2,
        reg_covar: float = 1e-6,
        n_init: int = 1,
        relevance: float | None = RELEVANCE,
        min_spread: MinimumSpread | None = None,
    ) -> None:
        super().__init__(n_states, n_iter, tol, reg_covar, n_init, min_spread)
        self.relevance = relevance

    def fit(  # type: ignore[override]
        self,
        X: np.ndarray,
        lengths: np.ndarray,
        sample_period: float,
        signal_names: list[str],
        poses: list[Mapping[str, Pose]],
        frame_names: list[str],
    ) -> "TPHSMM":
        """Learn from demonstrations in the base frame and the poses of their frames.

        Args:
            X: `N x D` samples of all demonstrations (base frame), concatenated.
            lengths: samples per demonstration.
            sample_period: seconds between samples.
            signal_names: the D signals; must include x, y and z.
            poses: per demonstration, frame name -> pose (`base` may be left out).
            frame_names: the P frames to learn in.
        """
        signal_names = list(signal_names)
        _check_positions(signal_names)
        if not frame_names or len(set(frame_names)) != len(frame_names):
            raise ModelError(f"frames must be distinct names (got {', '.join(frame_names) or 'none'})")
        lengths = np.asarray(lengths, dtype=int)
        if len(poses) != len(lengths):
            raise ModelError(f"{len(poses)} sets of frame poses for {len(lengths)} demonstrations")
        self.frame_names_ = list(frame_names)
        sequences = np.split(np.asarray(X, dtype=float), np.cumsum(lengths)[:-1])
        local = [
            np.hstack([_to_frame(sequence, _pose(demo_poses, name), signal_names) for name in self.frame_names_])
            for sequence, demo_poses in zip(sequences, poses)
        ]
        X = np.concatenate(local)
        if not set(QUATERNION_COLUMNS) & set(signal_names):
            return super().fit(X, lengths, sample_period, signal_names)  # type: ignore[return-value]
        D = len(signal_names)
        blocks = [to_model_columns(X[:, index * D : (index + 1) * D], signal_names) for index in range(len(self.frame_names_))]
        self.orientation_reference_ = np.array([reference for _, _, reference in blocks])
        return super().fit(np.hstack([block for block, _, _ in blocks]), lengths, sample_period, blocks[0][1])  # type: ignore[return-value]

    def at(self, poses: Mapping[str, Pose]) -> HSMM:
        """The skill for frames at `poses` (name -> pose; every frame but `base` required):
        an `HSMM` in the base frame whose state Gaussians are the products of the frames'."""
        self._check()
        if self.orientation is not None:
            return self._at_with_orientation(poses)
        D, names = len(self.signal_names_), self.signal_names_
        end = self.end_target()
        # The end point's Gaussian travels with the states' as one more row.
        local_means = self.means_ if end is None else np.vstack([self.means_, end[1]])
        local_covars = self.covars_ if end is None else np.concatenate([self.covars_, end[2][None]])
        means, covars = [], []
        for index, frame in enumerate(self.frame_names_):
            rotation, offset = _transform(_pose(poses, frame), names)
            block = slice(index * D, (index + 1) * D)
            means.append(local_means[:, block] @ rotation.T + offset)
            covars.append(rotation @ local_covars[:, block, block] @ rotation.T)
        base_means, base_covars = _product(means, covars, self.relevance)
        model = HSMM(self.n_states, self.n_iter, self.tol, self.reg_covar)
        model.means_, model.covars_ = base_means[: self.n_states], base_covars[: self.n_states]
        if end is not None:
            model.end_state_ = end[0]
            model.end_offsets_ = base_means[-1] - base_means[end[0]]
            model.end_covars_ = base_covars[-1]
        for name in ("duration_means_", "duration_stds_", "transmat_", "startprob_"):
            setattr(model, name, np.array(getattr(self, name), dtype=float))
        model.sample_period_, model.signal_names_, model.orientation_reference_ = self.sample_period_, list(names), None
        return model

    def _at_with_orientation(self, poses: Mapping[str, Pose]) -> HSMM:
        """`at` for a skill with orientation: each frame's state Gaussians (and the end point's)
        taken to the base frame, multiplied on R^n x S^3, and written as an `HSMM` whose rotation
        vectors are relative to the mean of the products' orientations."""
        D, names = len(self.signal_names_), self.signal_names_
        block = Coordinates.of(names)
        rows, covars = self.means_, self.covars_
        end = self.end_target()
        if end is not None:  # the end point's Gaussian travels with the states' as one more row
            rows, covars = np.vstack([rows, end[1]]), np.concatenate([covars, end[2][None]])
        frames = []  # per frame: (S x D base means with the rotation columns unused, S x 4 orientations, S x D x D covariances)
        for index, frame in enumerate(self.frame_names_):
            pose, columns = _pose(poses, frame), slice(index * D, (index + 1) * D)
            rotation, offset = _transform(pose, names)
            local = rows[:, columns]
            orientations = rotations.multiply(pose.orientation, rotations.exp_map(self.orientation[index], local[:, block.rotation]))
            frames.append((local @ rotation.T + offset, orientations, rotation @ covars[:, columns, columns] @ rotation.T))
        products = []
        for row in range(len(rows)):
            gaussians = [(means[row], turns[row], covariances[row]) for means, turns, covariances in frames]
            kept = relevant_frames([covariance for _, _, covariance in gaussians], self.relevance)
            products.append(_manifold_product([gaussians[index] for index in kept], block))
        reference = rotations.weighted_mean(np.array([turn for _, turn, _ in products[: self.n_states]]))
        base = np.array(
            [np.concatenate([mean[: block.rotation.start], rotations.log_map(reference, turn), mean[block.rotation.stop :]]) for mean, turn, _ in products]
        )
        model = HSMM(self.n_states, self.n_iter, self.tol, self.reg_covar)
        model.means_, model.covars_ = base[: self.n_states], np.array([covariance for _, _, covariance in products[: self.n_states]])
        if end is not None:
            model.end_state_ = end[0]
            model.end_offsets_ = block.deviations(base[-1], base[end[0]])
            model.end_covars_ = products[-1][2]
        for name in ("duration_means_", "duration_stds_", "transmat_", "startprob_"):
            setattr(model, name, np.array(getattr(self, name), dtype=float))
        model.sample_period_, model.signal_names_, model.orientation_reference_ = self.sample_period_, list(names), reference
        return model

    @property
    def feature_names(self) -> list[str]:
        return [f"{frame}.{name}" for frame in self.frame_names_ for name in self.signal_names_]

    def _frame_offset(self, frame: str | None) -> int:
        if frame is None:
            raise ModelError(f"the model has frames ({', '.join(self.frame_names_)}): say in which one the mean moves ('frame:')")
        if frame not in self.frame_names_:
            raise ModelError(f"the model has no frame {frame} (its frames: {', '.join(self.frame_names_)})")
        return self.frame_names_.index(frame) * len(self.signal_names_)

    def _check(self) -> None:
        if not hasattr(self, "frame_names_"):
            raise ModelError("the model has no frame_names_: fit it or load a model file first")
        super()._check()

    def _constrained(self, covars: np.ndarray) -> np.ndarray:
        """Zero the covariance between frames (each frame's block is kept)."""
        D = covars.shape[-1] // len(self.frame_names_)
        blocks = np.kron(np.eye(len(self.frame_names_)), np.ones((D, D)))
        return covars * blocks


def _check_positions(signal_names: list[str]) -> None:
    missing = [name for name in POSITION_SIGNALS if name not in signal_names]
    if missing:
        raise ModelError(f"frames move positions, but the demonstrations have no {', '.join(missing)} column")


def _pose(poses: Mapping[str, Pose], frame: str) -> Pose:
    if frame == BASE_FRAME:
        return poses.get(BASE_FRAME, Pose())
    if frame not in poses:
        raise ModelError(f"no pose for frame {frame} (given: {', '.join(poses) or 'none'})")
    return poses[frame]


def _transform(pose: Pose, signal_names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """`D x D` rotation and `D` offset taking frame coordinates to the base frame."""
    D = len(signal_names)
    columns = [signal_names.index(name) for name in POSITION_SIGNALS]
    rotation, offset = np.eye(D), np.zeros(D)
    rotation[np.ix_(columns, columns)] = pose.rotation
    offset[columns] = pose.position
    return rotation, offset


def _to_frame(samples: np.ndarray, pose: Pose, signal_names: list[str]) -> np.ndarray:
    """`T x D` base-frame samples expressed in the frame at `pose` (an orientation's quaternion
    columns too)."""
    rotation, offset = _transform(pose, signal_names)
    local = (samples - offset) @ rotation
    if set(QUATERNION_COLUMNS) <= set(signal_names):
        columns = [signal_names.index(name) for name in QUATERNION_COLUMNS]
        local[:, columns] = rotations.multiply(rotations.conjugate(pose.orientation), samples[:, columns])
    return local


def _manifold_product(
    gaussians: list[tuple[np.ndarray, np.ndarray, np.ndarray]], block: Coordinates, iterations: int = 50
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The product of Gaussians on R^n x S^3, each `(D mean, 4 orientation, D x D covariance)`
    with the orientation's covariance in the tangent space at its own mean (columns `block`):
    Gauss-Newton in the tangent space at the current estimate, each covariance transported
    there, until the step is below 1e-12. Returns the mean (its rotation columns unused), the
    orientation and the covariance at it. One Gaussian is returned as it is."""
    if len(gaussians) == 1:
        return gaussians[0]
    mean, turn = np.array(gaussians[0][0], dtype=float), gaussians[0][1]
    for _ in range(iterations):
        information, weighted = 0.0, 0.0
        for other_mean, other_turn, covariance in gaussians:
            deviation = other_mean - mean
            deviation[block.rotation] = rotations.log_map(turn, other_turn)
            transport = np.eye(len(mean))
            transport[block.rotation, block.rotation] = rotations.transport(other_turn, turn)
            precision = np.linalg.inv(transport @ covariance @ transport.T)
            information, weighted = information + precision, weighted + precision @ deviation
        step = np.linalg.solve(information, weighted)
        mean = mean + step
        turn = rotations.exp_map(turn, step[block.rotation])
        if np.linalg.norm(step) < 1e-12:
            break
    covariance = np.linalg.inv(information)
    return mean, turn, (covariance + covariance.T) / 2


def relevant_frames(covariances: list[np.ndarray], relevance: float | None) -> list[int]:
    """The frames (indices) whose Gaussian enters a state's product: those whose position
    block (`x, y, z`, the first three columns) has a geometric-mean variance at most
    `relevance` times the smallest (all of them for None).

    Why: the demonstrations' objects all stand at one height, so every frame sees the vertical
    spread of the same motion and some frame always looks as certain as the relevant one in
    that direction, along an axis that is tilted a little by chance. At the insertion's end
    such a frame (the shaft's original pose, or the base) then pulled the product by up to
    5 mm in x and y at new placements, although its x-y spread was ten times the holder's.
    A frame that far less certain than the best one carries no information about the state
    that the best one lacks."""
    if relevance is None or len(covariances) == 1:
        return list(range(len(covariances)))
    spreads = np.array([max(np.linalg.det(covariance[:3, :3]), 0.0) ** (1 / 3) for covariance in covariances])
    return [index for index, spread in enumerate(spreads) if spread <= relevance * spreads.min()]


def _product(means: list[np.ndarray], covars: list[np.ndarray], relevance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Product of Gaussians, state by state: `K x D` means and `K x D x D` covariances, each
    state over its `relevant_frames`. One frame is returned as it is, so that a model with
    the base frame alone is the plain HSMM."""
    if len(means) == 1:
        return means[0], covars[0]
    if relevance is not None:
        products = []
        for state in range(len(means[0])):
            kept = relevant_frames([covar[state] for covar in covars], relevance)
            products.append(_product([means[index][state : state + 1] for index in kept], [covars[index][state : state + 1] for index in kept]))
        return np.concatenate([mean for mean, _ in products]), np.concatenate([covar for _, covar in products])
    precisions = [np.linalg.inv(covar) for covar in covars]
    covar = np.linalg.inv(np.sum(precisions, axis=0))
    weighted = np.sum([np.einsum("kde,ke->kd", precision, mean) for precision, mean in zip(precisions, means)], axis=0)
    covar = (covar + np.swapaxes(covar, 1, 2)) / 2
    return np.einsum("kde,ke->kd", covar, weighted), covar
