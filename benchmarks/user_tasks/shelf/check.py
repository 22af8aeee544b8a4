"""Was the shelf task physically achieved at the end of a rollout?

done(signals, scene_path) looks at the last half second of the recorded object poses (box_x,
box_y, box_z, box_qx..box_qw, box_held, and the shelf frame's shelf_x, shelf_y, shelf_z) and at
the scene's geometry (read from scene.yaml), not at the spec: the box rests on the shelf's top
(its bottom face within 5 mm of it, not moving), upright (within about 6 degrees), inside the
2 x 2 cm target area around the shelf frame's origin, and out of the fingers.

    python check.py SIGNALS.csv [scene.yaml]
"""

import sys
from pathlib import Path

import numpy as np
import yaml

TARGET_HALF_WIDTH = 0.01  # the marked spot: 2 x 2 cm
UPRIGHT_COS = np.cos(0.1)


def _columns(signals):
    if isinstance(signals, (str, Path)):
        data = np.genfromtxt(signals, delimiter=",", names=True)
        return {name: data[name] for name in data.dtype.names}
    return getattr(signals, "columns", signals)


def _objects(scene):
    return {item["name"]: item for item in scene["objects"]}


def _up_axis_z(qx, qy, qz, qw):
    """z component of the object's own z axis (1 when upright)."""
    return 1.0 - 2.0 * (qx**2 + qy**2)


def done(signals, scene_path) -> bool:
    c = _columns(signals)
    scene = yaml.safe_load(Path(scene_path).read_text())
    objects, frames = _objects(scene), scene["frames"]
    box_half_height = objects["box"]["size"][2]
    shelf = objects["shelf"]
    # the shelf's top, relative to the shelf frame's origin (which moves with the shelf)
    top_in_frame = shelf["position"][2] + shelf["size"][2] - frames["shelf"]["position"][2]
    t = np.asarray(c["t"])
    last = t >= t[-1] - 0.5
    box = np.stack([np.asarray(c[f"box_{k}"])[last] for k in "xyz"], axis=1)
    top = np.stack([np.asarray(c[f"shelf_{k}"])[last] for k in "xyz"], axis=1) + [0, 0, top_in_frame]
    up = _up_axis_z(*(np.asarray(c[f"box_q{k}"])[last] for k in "xyzw"))
    released = np.all(np.asarray(c["box_held"])[last] < 0.5)
    still = np.ptp(box, axis=0).max() < 0.002
    in_area = np.all(np.abs(box[:, :2] - top[:, :2]) <= TARGET_HALF_WIDTH)
    resting = np.all(np.abs(box[:, 2] - box_half_height - top[:, 2]) < 0.005)
    upright = np.all(up > UPRIGHT_COS)
    return bool(released and still and in_area and resting and upright)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else here / "scene.yaml"))
