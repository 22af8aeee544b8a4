"""Object poses: a position in the robot base frame and an orientation: a yaw about the vertical
axis, or any rotation (a unit quaternion).

A leaf module shared by the skill models (task-parameterised HSMMs are learned in the frames
of the objects) and the scenes (objects are placed at poses); it imports neither.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_YAW
from stl_lfd.yamlfile import check_keys, number, vector

BASE_FRAME = "base"  # the robot base frame: always at the origin, never placed


@dataclass(frozen=True)
class Pose:
    """`position` (x, y, z, metres) of a frame in the base frame, and its orientation: `yaw`
    (radians, about z), or `quaternion` (x, y, z, w; unit), a full orientation that replaces
    the yaw when given."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw: float = 0.0
    quaternion: tuple[float, float, float, float] | None = None

    @property
    def orientation(self) -> np.ndarray:
        """The frame's orientation as a unit quaternion (x, y, z, w)."""
        return np.asarray(self.quaternion, dtype=float) if self.quaternion is not None else rotations.from_yaw(self.yaw)

    @property
    def turns_about_z_only(self) -> bool:
        """Whether the orientation is a yaw (scenes move their objects by such poses only)."""
        return self.quaternion is None

    @property
    def rotation(self) -> np.ndarray:
        """`3 x 3` rotation from the frame to the base frame."""
        if self.quaternion is not None:
            return rotations.to_matrix(self.orientation)
        cos, sin = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])

    def to_base(self, points: np.ndarray) -> np.ndarray:
        """`N x 3` points given in this frame, expressed in the base frame."""
        return np.asarray(points) @ self.rotation.T + np.asarray(self.position)

    def from_base(self, points: np.ndarray) -> np.ndarray:
        """`N x 3` base-frame points, expressed in this frame."""
        return (np.asarray(points) - np.asarray(self.position)) @ self.rotation

    def compose(self, other: "Pose") -> "Pose":
        """This transform applied after `other`: the pose `other` takes when the whole world
        is moved by this one."""
        position = tuple(float(v) for v in self.to_base(np.asarray(other.position)[None])[0])
        if self.turns_about_z_only and other.turns_about_z_only:
            return Pose(position, self.yaw + other.yaw)
        return Pose(position, quaternion=tuple(float(v) for v in rotations.multiply(self.orientation, other.orientation)))

    def as_dict(self) -> dict[str, Any]:
        if self.quaternion is not None:
            return {"position": [float(v) for v in self.position], "orientation": [float(v) for v in self.quaternion]}
        return {"position": [float(v) for v in self.position], "yaw": float(self.yaw)}


def parse_pose(data: Any, path: Path | str, where: str) -> Pose:
    """A pose from YAML: `{position: [x, y, z], yaw: RAD}` (yaw optional, default 0) or
    `{position: [x, y, z], orientation: [qx, qy, qz, qw]}` (a unit quaternion, scalar last;
    normalised when its norm is within 0.001 of 1)."""
    check_keys(data, ("position", "yaw", "orientation"), path, where, required=("position",))
    position = vector(data["position"], 3, path, f"{where}.position")
    if "orientation" not in data:
        yaw = number(data.get("yaw", 0.0), path, f"{where}.yaw")
        if abs(yaw) > MAX_YAW:
            raise ConfigError(f"{path}: '{where}.yaw' must be in radians, within two turns either way (got {yaw:g})")
        return Pose(position, yaw)
    if "yaw" in data:
        raise ConfigError(f"{path}: '{where}' gives both 'yaw' and 'orientation'; give one")
    quaternion = np.array(vector(data["orientation"], 4, path, f"{where}.orientation"))
    norm = float(np.linalg.norm(quaternion))
    if not abs(norm - 1.0) <= rotations.UNIT_TOLERANCE:
        raise ConfigError(f"{path}: '{where}.orientation' must be a unit quaternion [qx, qy, qz, qw] (its norm is {norm:.4g})")
    return Pose(position, quaternion=tuple(float(v) for v in quaternion / norm))


def parse_assignment(text: str, option: str, defaults: Mapping[str, Pose] | None = None) -> tuple[str, Pose]:
    """`NAME=x,y,z[,yaw]` from the command line (metres, yaw in radians).

    With `defaults` (frame name -> current pose, as a scene has them), NAME must be one of
    them and `NAME=x,y[,z[,yaw]]` keeps the default's z and yaw when left out."""
    name, equals, numbers = text.partition("=")
    name = name.strip()
    shape = "NAME=x,y[,z[,yaw]]" if defaults is not None else "NAME=x,y,z[,yaw]"
    usage = f"{option} {text}: expected {shape} (metres, yaw in radians)"
    if not equals or not name:
        raise ConfigError(usage)
    if defaults is not None and name not in defaults:
        raise ConfigError(f"{option} {text}: no frame '{name}' (frames: {', '.join(defaults) or 'none'})")
    try:
        values = [float(part) for part in numbers.split(",")]
    except ValueError:
        raise ConfigError(usage) from None
    shortest = 2 if defaults is not None else 3
    if not shortest <= len(values) <= 4 or not all(math.isfinite(v) for v in values):
        raise ConfigError(usage)
    if len(values) == 4 and abs(values[3]) > MAX_YAW:
        raise ConfigError(f"{option} {text}: the yaw must be in radians, within two turns either way (got {values[3]:g})")
    return name, pose_from_values(values, defaults[name] if defaults is not None else Pose())


def pose_from_values(values: list[float], default: Pose) -> Pose:
    """A pose from `[x, y]`, `[x, y, z]` or `[x, y, z, yaw]`, the rest from `default`."""
    position = (values[0], values[1], values[2] if len(values) > 2 else default.position[2])
    return Pose(position, values[3] if len(values) > 3 else default.yaw)
