"""Was the tray task physically achieved at the end of a rollout?

done(signals, scene_path) looks at the last half second of the recorded object poses (can_x,
can_y, can_z, can_qx..can_qw, can_held, and the tray frame's tray_x, tray_y, tray_z) and at the
scene's geometry (read from scene.yaml), not at the spec: the can stands on the tray's floor
(its bottom within 5 mm of the floor's top, not moving), upright (within about 6 degrees),
entirely inside the walls, and out of the fingers.

    python check.py SIGNALS.csv [scene.yaml]
"""

import sys
from pathlib import Path

import numpy as np
import yaml

UPRIGHT_COS = np.cos(0.1)


def _columns(signals):
    if isinstance(signals, (str, Path)):
        data = np.genfromtxt(signals, delimiter=",", names=True)
        return {name: data[name] for name in data.dtype.names}
    return getattr(signals, "columns", signals)


def _up_axis_z(qx, qy, qz, qw):
    """z component of the object's own z axis (1 when upright)."""
    return 1.0 - 2.0 * (qx**2 + qy**2)


def _inside(scene):
    """The tray's floor top (z) and the half-widths of its inside (x, y), relative to the tray
    frame's origin, from its walls: the inner face of the nearest wall on each side."""
    objects = {item["name"]: item for item in scene["objects"]}
    frame = scene["frames"]["tray"]
    origin = np.asarray(frame["position"], dtype=float)
    floor = objects["tray_floor"]
    floor_top = floor["position"][2] + floor["size"][2] - origin[2]
    half = [np.inf, np.inf]
    for name in frame["objects"]:
        if name == "tray_floor":
            continue
        wall = objects[name]
        offset = np.asarray(wall["position"], dtype=float) - origin
        axis = 0 if abs(offset[0]) > abs(offset[1]) else 1  # the wall bounds the inside along this axis
        half[axis] = min(half[axis], abs(offset[axis]) - wall["size"][axis])
    return floor_top, np.array(half)


def done(signals, scene_path) -> bool:
    c = _columns(signals)
    scene = yaml.safe_load(Path(scene_path).read_text())
    objects = {item["name"]: item for item in scene["objects"]}
    radius, height = objects["can"]["size"]  # a cylinder: radius and full height
    floor_top, half = _inside(scene)
    t = np.asarray(c["t"])
    last = t >= t[-1] - 0.5
    can = np.stack([np.asarray(c[f"can_{k}"])[last] for k in "xyz"], axis=1)
    tray = np.stack([np.asarray(c[f"tray_{k}"])[last] for k in "xyz"], axis=1)
    up = _up_axis_z(*(np.asarray(c[f"can_q{k}"])[last] for k in "xyzw"))
    released = np.all(np.asarray(c["can_held"])[last] < 0.5)
    still = np.ptp(can, axis=0).max() < 0.002
    between_walls = np.all(np.abs(can[:, :2] - tray[:, :2]) <= half - radius + 0.001)
    on_floor = np.all(np.abs(can[:, 2] - height / 2 - (tray[:, 2] + floor_top)) < 0.005)
    upright = np.all(up > UPRIGHT_COS)
    return bool(released and still and between_walls and on_floor and upright)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else here / "scene.yaml"))
