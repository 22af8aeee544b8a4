"""Skills with orientation: the model's coordinates when the demonstrations carry the hand's
orientation (`qx, qy, qz, qw`).

A pose skill keeps the position (and any other signal) as it is and the orientation as a
rotation vector `rx, ry, rz` relative to one reference quaternion of the skill (the mean of
every demonstrated orientation): `q = reference * exp(r)`. These are the model's columns, so
state means move, are bounded and optimised like positions. The Gaussians themselves live on
R^n x S^3: a state's orientation covariance is in the tangent space at the state's own mean
orientation (`rotations.log_map`), its mean is the weighted mean on the sphere (iterated
averaging), and the tracker sees each covariance transported to the reference's tangent space
(Zeestraten et al., RA-L 2017; Calinon, IEEE RAM 2020). A skill turning by up to about half a
turn either side of its mean orientation is represented without wrapping.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ModelError
from stl_lfd.rotations import QUATERNION_COLUMNS, ROTATION_COLUMNS


@dataclass(frozen=True)
class Coordinates:
    """Which of a model's `D` columns hold a rotation vector (`rotation`, 3 columns), if any."""

    rotation: slice | None = None

    @classmethod
    def of(cls, names: list[str]) -> "Coordinates":
        """The coordinates of a model whose columns are `names`."""
        if not set(ROTATION_COLUMNS) & set(names):
            return cls()
        start = names.index(ROTATION_COLUMNS[0]) if ROTATION_COLUMNS[0] in names else -1
        if start < 0 or tuple(names[start : start + 3]) != ROTATION_COLUMNS:
            raise ModelError(f"a model's orientation must be the columns rx, ry, rz in that order (got {', '.join(names)})")
        return cls(slice(start, start + 3))

    def deviations(self, points: np.ndarray, mean: np.ndarray) -> np.ndarray:
        """`... x D` deviations of points from a state's `D` mean: differences, and for the
        orientation the tangent vector at the mean's orientation."""
        deviation = np.asarray(points, dtype=float) - mean
        if self.rotation is not None:
            deviation[..., self.rotation] = rotations.log_map(rotations.from_rotvec(mean[self.rotation]), rotations.from_rotvec(points[..., self.rotation]))
        return deviation

    def mean(self, points: np.ndarray, weights: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
        """The weighted mean of `N x D` points: the average, and for the orientation the mean on
        the sphere (from `start`'s orientation, if given)."""
        mean = weights @ points / max(float(weights.sum()), 1e-300)
        if self.rotation is not None:
            begin = None if start is None else rotations.from_rotvec(start[self.rotation])
            quaternion = rotations.weighted_mean(rotations.from_rotvec(points[:, self.rotation]), weights, begin)
            mean[self.rotation] = rotations.to_rotvec(quaternion)
        return mean

    def shifted(self, mean: np.ndarray, deviations: np.ndarray) -> np.ndarray:
        """`... x D` points at `deviations` from `mean` (the inverse of `deviations`)."""
        points = mean + np.asarray(deviations, dtype=float)
        if self.rotation is not None:
            moved = rotations.exp_map(rotations.from_rotvec(mean[self.rotation]), deviations[..., self.rotation])
            points[..., self.rotation] = rotations.to_rotvec(moved)
        return points

    def at_reference(self, means: np.ndarray, covariances: np.ndarray) -> np.ndarray:
        """`S x D x D` covariances with their orientation block transported from each state's
        mean orientation (`S x D` means) to the reference's tangent space, where the tracker
        works (see `rotations.transport`)."""
        if self.rotation is None:
            return covariances
        moved = np.array(covariances, dtype=float)
        for index, mean in enumerate(means):
            transport = np.eye(mean.shape[0])
            transport[self.rotation, self.rotation] = rotations.transport(rotations.from_rotvec(mean[self.rotation]), rotations.IDENTITY)
            moved[index] = transport @ moved[index] @ transport.T
        return moved


def to_model_columns(X: np.ndarray, names: list[str]) -> tuple[np.ndarray, list[str], np.ndarray | None]:
    """Demonstration samples (`N x D`, columns `names`) in a model's coordinates: the quaternion
    columns `qx, qy, qz, qw` replaced, where they stood, by the rotation vector `rx, ry, rz`
    relative to the samples' mean orientation, which is returned as the reference (None, and
    the samples unchanged, without orientation)."""
    present = [name for name in QUATERNION_COLUMNS if name in names]
    if not present:
        return X, list(names), None
    if len(present) != 4:
        raise ModelError(f"an orientation needs all of qx, qy, qz, qw (the demonstrations have only {', '.join(present)})")
    columns = [names.index(name) for name in QUATERNION_COLUMNS]
    quaternions = rotations.continuous(X[:, columns] / np.linalg.norm(X[:, columns], axis=1, keepdims=True))
    reference = rotations.weighted_mean(quaternions, start=quaternions[0])
    kept = [index for index in range(len(names)) if index not in columns]
    at = sum(1 for index in kept if index < columns[0])
    values = np.insert(X[:, kept], [at] * 3, rotations.log_map(reference, quaternions), axis=1)
    model_names = [names[index] for index in kept]
    return values, model_names[:at] + list(ROTATION_COLUMNS) + model_names[at:], reference
