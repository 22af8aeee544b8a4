"""The geometry of the scenes' primitive shapes (a box, a cylinder, a sphere, sized as
`SceneObject.size` says): distances to them, their lowest points and their extents along any
direction, at any pose."""

from __future__ import annotations

import numpy as np

import stl_lfd.rotations as rotations

SHAPES = ("box", "cylinder", "sphere")


def distance_to_shape(shape: str, size: tuple[float, ...], point: np.ndarray) -> float:
    """Distance from `point` (in the object's frame) to a box (half extents), a cylinder
    (radius, height; along z) or a sphere (radius); 0 inside."""
    if shape == "box":
        return float(np.linalg.norm(np.maximum(np.abs(point) - np.asarray(size), 0.0)))
    if shape == "cylinder":
        radius, height = size[0], size[1]
        return float(np.hypot(max(np.hypot(point[0], point[1]) - radius, 0.0), max(abs(point[2]) - height / 2, 0.0)))
    return float(max(np.linalg.norm(point) - size[0], 0.0))


def lowest_heights(shape: str, size: tuple[float, ...], centres: np.ndarray, orientations: np.ndarray) -> np.ndarray:
    """`S` heights (m) of the lowest point of a box, cylinder or sphere (`size` as `SceneObject`'s)
    whose centre is at `centres` (`S x 3`) and turned by `orientations` (`S x 4` quaternions)."""
    centres = np.asarray(centres, dtype=float)
    if shape == "sphere":
        return centres[:, 2] - size[0]
    axes_z = rotations.to_matrix(orientations)[:, 2, :]  # S x 3: the height of each body axis
    if shape == "box":
        return centres[:, 2] - np.abs(axes_z) @ np.asarray(size, dtype=float)
    radius, height = size[0], size[1]
    vertical = np.clip(np.abs(axes_z[:, 2]), 0.0, 1.0)
    return centres[:, 2] - height / 2 * vertical - radius * np.sqrt(1.0 - vertical**2)


def extents_along(shape: str, size: tuple[float, ...], orientations: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """`S x A` half extents of a box, cylinder or sphere (`size` as `SceneObject`'s) turned by
    `orientations` (`S x 4`) along each of `S x A x 3` unit `axes`: how far the shape reaches
    from its centre in that direction (its support function)."""
    if shape == "sphere":
        return np.full(axes.shape[:2], size[0])
    local = np.einsum("sji,saj->sai", rotations.to_matrix(orientations), axes)  # the axes in the object's frame
    if shape == "box":
        return np.abs(local) @ np.asarray(size, dtype=float)
    along = np.clip(np.abs(local[..., 2]), 0.0, 1.0)  # a cylinder's axis is its z
    return size[1] / 2 * along + size[0] * np.sqrt(1.0 - along**2)
