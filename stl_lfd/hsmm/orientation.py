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
    """Which of a model's `D` columns hold rotation vectors: `rotations`, one 3-column slice per
    orientation (one per frame of a TP-HSMM), none for positions only."""

    rotations: tuple[slice, ...] = ()

    @classmethod
    def of(cls, names: list[str]) -> "Coordinates":
        """The coordinates of a model whose columns are `names` (`rx` or `FRAME.rx` and so on)."""
        bare = [name.rsplit(".", 1)[-1] for name in names]
        starts = [index for index, name in enumerate(bare) if name == ROTATION_COLUMNS[0]]
        if any(tuple(bare[start : start + 3]) != ROTATION_COLUMNS for start in starts) or bare.count("ry") != len(starts) or bare.count("rz") != len(starts):
            raise ModelError(f"a model's orientation must be the columns rx, ry, rz in that order (got {', '.join(names)})")
        return cls(tuple(slice(start, start + 3) for start in starts))

    @property
    def rotation(self) -> slice | None:
        """The rotation vector's columns of a model in one frame (None without orientation)."""
        return self.rotations[0] if self.rotations else None

    def deviations(self, points: np.ndarray, mean: np.ndarray) -> np.ndarray:
        """`... x D` deviations of points from a state's `D` mean: differences, and for an
        orientation the tangent vector at the mean's orientation."""
        deviation = np.asarray(points, dtype=float) - mean
        for block in self.rotations:
            deviation[..., block] = rotations.log_map(rotations.from_rotvec(mean[block]), rotations.from_rotvec(points[..., block]))
        return deviation

    def mean(self, points: np.ndarray, weights: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
        """The weighted mean of `N x D` points: the average, and for an orientation the mean on
        the sphere (from `start`'s orientation, if given)."""
        mean = weights @ points / max(float(weights.sum()), 1e-300)
        for block in self.rotations:
            begin = None if start is None else rotations.from_rotvec(start[block])
            mean[block] = rotations.to_rotvec(rotations.weighted_mean(rotations.from_rotvec(points[:, block]), weights, begin))
        return mean

    def shifted(self, mean: np.ndarray, deviations: np.ndarray) -> np.ndarray:
        """`... x D` points at `deviations` from `mean` (the inverse of `deviations`)."""
        deviations = np.asarray(deviations, dtype=float)
        points = mean + deviations
        for block in self.rotations:
            points[..., block] = rotations.to_rotvec(rotations.exp_map(rotations.from_rotvec(mean[block]), deviations[..., block]))
        return points

    def transport(self, mean: np.ndarray, target: np.ndarray) -> np.ndarray:
        """`D x D`: tangent vectors at `mean`'s orientations carried to `target`'s (quaternions,
        one row per orientation), the other columns unchanged (see `rotations.transport`)."""
        matrix = np.eye(mean.shape[0])
        for block, to in zip(self.rotations, np.atleast_2d(target)):
            matrix[block, block] = rotations.transport(rotations.from_rotvec(mean[block]), to)
        return matrix

    def at_reference(self, means: np.ndarray, covariances: np.ndarray) -> np.ndarray:
        """`S x D x D` covariances with their orientation blocks transported from each state's
        mean orientation (`S x D` means) to the reference's tangent space, where the tracker
        works."""
        if not self.rotations:
            return covariances
        identities = np.tile(rotations.IDENTITY, (len(self.rotations), 1))
        moved = []
        for mean, covariance in zip(means, covariances):
            transport = self.transport(mean, identities)
            moved.append(transport @ covariance @ transport.T)
        return np.array(moved)


def to_model_columns(X: np.ndarray, names: list[str], reference: np.ndarray | None = None) -> tuple[np.ndarray, list[str], np.ndarray | None]:
    """Demonstration samples (`N x D`, columns `names`) in a model's coordinates: the quaternion
    columns `qx, qy, qz, qw` replaced, where they stood, by the rotation vector `rx, ry, rz`
    relative to `reference` (default: the samples' mean orientation), which is returned (None,
    and the samples unchanged, without orientation)."""
    present = [name for name in QUATERNION_COLUMNS if name in names]
    if not present:
        return X, list(names), None
    if len(present) != 4:
        raise ModelError(f"an orientation needs all of qx, qy, qz, qw (the demonstrations have only {', '.join(present)})")
    columns = [names.index(name) for name in QUATERNION_COLUMNS]
    quaternions = rotations.continuous(X[:, columns] / np.linalg.norm(X[:, columns], axis=1, keepdims=True))
    if reference is None:
        reference = rotations.weighted_mean(quaternions, start=quaternions[0])
    kept = [index for index in range(len(names)) if index not in columns]
    at = sum(1 for index in kept if index < columns[0])
    values = np.insert(X[:, kept], [at] * 3, rotations.log_map(reference, quaternions), axis=1)
    model_names = [names[index] for index in kept]
    return values, model_names[:at] + list(ROTATION_COLUMNS) + model_names[at:], reference
