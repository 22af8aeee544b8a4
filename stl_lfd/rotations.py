"""Unit quaternions `(x, y, z, w)` (scalar last, as ROS and scipy write them), rotation vectors,
and the maps between the sphere of unit quaternions S^3 and its tangent spaces.

The tangent space at a quaternion `g` is written in `g`'s own (body) axes: `log_map(g, q)` is
the rotation vector (axis times angle, radians) of the rotation that takes `g` to `q`, so
`q = g * exp(r)`. Moving every quaternion by one rotation on the left (a change of world
frame) leaves these vectors unchanged, which is what lets a skill's orientation covariance
travel with the object it refers to (Zeestraten et al., "An Approach for Imitation Learning on
Riemannian Manifolds", RA-L 2017; Calinon, "Gaussians on Riemannian Manifolds", IEEE RAM 2020).

Arrays hold one quaternion or rotation vector per row: `... x 4` and `... x 3`. A leaf module
(numpy only), shared by the skill models, the scenes and the backends.
"""

from __future__ import annotations

import functools

import numpy as np

from stl_lfd.errors import SignalError

QUATERNION_COLUMNS = ("qx", "qy", "qz", "qw")
ROTATION_COLUMNS = ("rx", "ry", "rz")
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
# The hand pointing straight down (its approach axis, local z, along the base's -z): a half
# turn about x. Skills without orientation execute with it.
DOWN = np.array([1.0, 0.0, 0.0, 0.0])
UNIT_TOLERANCE = 1e-3  # a quaternion whose norm is off 1 by more than this is refused, not normalised


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The Hamilton product `a * b` (the rotation `b`, then `a`), row by row."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """The inverse rotation of unit quaternions."""
    return np.asarray(q, dtype=float) * np.array([-1.0, -1.0, -1.0, 1.0])


def from_rotvec(r: np.ndarray) -> np.ndarray:
    """`... x 3` rotation vectors -> `... x 4` unit quaternions."""
    r = np.asarray(r, dtype=float)
    angle = np.linalg.norm(r, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(half) / angle, with its series near 0 (1/2 - angle^2/48)
    scale = np.where(angle > 1e-8, np.sin(half) / np.where(angle > 1e-8, angle, 1.0), 0.5 - angle**2 / 48.0)
    return np.concatenate([r * scale, np.cos(half)], axis=-1)


def to_rotvec(q: np.ndarray) -> np.ndarray:
    """`... x 4` unit quaternions -> `... x 3` rotation vectors of angle at most pi (q and -q give the same)."""
    q = np.asarray(q, dtype=float)
    q = np.where(q[..., 3:] < 0, -q, q)
    vector, w = q[..., :3], np.clip(q[..., 3:], -1.0, 1.0)
    sine = np.linalg.norm(vector, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(sine, w)
    scale = np.where(sine > 1e-8, angle / np.where(sine > 1e-8, sine, 1.0), 2.0 / np.maximum(w, 1e-300))
    return vector * scale


def log_map(base: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The tangent vectors at `base` (body axes, radians) of the rotations `q`: `base * exp(r) = q`."""
    return to_rotvec(multiply(conjugate(base), q))


def exp_map(base: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The quaternions `base * exp(r)` of tangent vectors `r` at `base`."""
    return multiply(base, from_rotvec(r))


def rotate(q: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """`... x 3` vectors rotated by `q`."""
    return np.asarray(vectors, dtype=float) @ to_matrix(q).swapaxes(-1, -2) if np.ndim(q) == 1 else np.einsum("...ij,...j->...i", to_matrix(q), vectors)


def to_matrix(q: np.ndarray) -> np.ndarray:
    """`... x 3 x 3` rotation matrices of unit quaternions."""
    x, y, z, w = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def from_yaw(yaw: float) -> np.ndarray:
    """The quaternion of a rotation by `yaw` radians about z."""
    return np.array([0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])


def transport(base: np.ndarray, target: np.ndarray) -> np.ndarray:
    """`3 x 3`: the parallel transport of tangent vectors (body axes) from `base` to `target`
    along the geodesic between them. On S^3 with its bi-invariant metric it is the rotation
    by minus half the relative rotation: a covariance `S` at `base` is `T S T'` at `target`."""
    return to_matrix(from_rotvec(-0.5 * log_map(base, target)))


def weighted_mean(q: np.ndarray, weights: np.ndarray | None = None, start: np.ndarray | None = None, iterations: int = 20) -> np.ndarray:
    """The weighted (Karcher) mean of `n x 4` unit quaternions by iterated averaging in the
    tangent space (Gauss-Newton): `g <- g * exp(sum w log_g(q) / sum w)` until the step is
    below 1e-12 rad. `start`: the first estimate (default: the quaternion of largest weight)."""
    q = np.asarray(q, dtype=float)
    weights = np.ones(len(q)) if weights is None else np.asarray(weights, dtype=float)
    mean = q[int(np.argmax(weights))] if start is None else np.asarray(start, dtype=float)
    total = max(float(weights.sum()), 1e-300)
    for _ in range(iterations):
        step = weights @ log_map(mean, q) / total
        mean = exp_map(mean, step)
        if np.linalg.norm(step) < 1e-12:
            break
    return mean / np.linalg.norm(mean)


def continuous(q: np.ndarray) -> np.ndarray:
    """`T x 4` quaternions with signs flipped where needed so that each is on the same side as
    the one before (q and -q are the same rotation; a path on S^3 must not jump between them)."""
    q = np.array(q, dtype=float)
    if len(q) < 2:
        return q
    # Sample i is flipped when its product with sample i - 1 *as left* is negative, which is
    # the product with the original sample i - 1, negated if that one was flipped: so the flips
    # alternate with every negative product and start over (unflipped) where it is 0 or NaN.
    products = np.einsum("ij,ij->i", q[1:], q[:-1])
    negative = products < 0
    restarts = ~(negative | (products > 0))
    count = np.concatenate(([0], np.cumsum(negative)))
    restart_at = np.maximum.accumulate(np.where(np.concatenate(([True], restarts)), np.arange(len(q)), 0))
    flipped = (count - count[restart_at]) % 2 == 1
    q[flipped] = -q[flipped]
    return q


def checked_quaternions(q: np.ndarray, source: str) -> np.ndarray:
    """`T x 4` quaternions of the samples of `source` (a signal CSV: sample i is on line i + 2,
    after the header), normalised and made continuous; SignalError naming the line for a NaN or
    a norm off 1 by more than UNIT_TOLERANCE (not a rotation: a unit or column mix-up)."""
    q = np.asarray(q, dtype=float)
    norms = np.linalg.norm(q, axis=-1)
    bad = np.flatnonzero(~np.isfinite(norms) | (np.abs(norms - 1.0) > UNIT_TOLERANCE))
    if bad.size:
        row = int(bad[0])
        shown = ",".join(f"{value:g}" for value in q[row])
        raise SignalError(f"{source}:{row + 2}: qx,qy,qz,qw = {shown} is not a unit quaternion (norm {norms[row]:.4g}; expected 1 within {UNIT_TOLERANCE:g})")
    return continuous(q / norms[:, None])


def tilt(q: np.ndarray) -> np.ndarray:
    """The angle (rad) between the hand's approach axis (its local z) and straight down."""
    return np.arccos(np.clip(-_vertical_of_z(q), -1.0, 1.0))


def uprightness(q: np.ndarray) -> np.ndarray:
    """The angle (rad, 0 to pi/2) between an object's z axis and the vertical, either way up: a
    cylinder's axis has no direction (0 for an upright shaft, pi/2 for a lying one)."""
    return np.arccos(np.clip(np.abs(_vertical_of_z(q)), 0.0, 1.0))


def _vertical_of_z(q: np.ndarray) -> np.ndarray:
    """The vertical component of the local z axis: `to_matrix(q)[..., 2, 2]`, alone."""
    q = np.asarray(q, dtype=float)
    x, y = q[..., 0], q[..., 1]
    return 1 - 2 * (x * x + y * y)


def from_euler(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """The quaternion of roll, pitch and yaw (rad) as PyBullet and scenes give them: about x,
    then y, then z, all fixed axes."""
    return _euler_quaternion(float(roll), float(pitch), float(yaw)).copy()


@functools.lru_cache(maxsize=256)
def _euler_quaternion(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """`from_euler`, kept: scenes ask for the same few orientations at every execution."""
    return multiply(from_rotvec([0.0, 0.0, yaw]), multiply(from_rotvec([0.0, pitch, 0.0]), from_rotvec([roll, 0.0, 0.0])))
