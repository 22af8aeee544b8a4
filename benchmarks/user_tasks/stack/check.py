"""Was the stack task physically achieved at the end of a rollout?

done(signals, scene_path) looks at the last half second of the recorded object poses (block_x,
block_y, block_z, block_qx..block_qw, block_held, and the lower block's lower_x, lower_y, lower_z,
lower_qx..lower_qw) and at the scene's geometry (read from scene.yaml), not at the spec: the cube
rests on the lower block's top (its bottom face within 4 mm of it, not moving), centred on it
within 8 mm, both blocks upright (within about 6 degrees), and the cube is out of the fingers.

    python check.py SIGNALS.csv [scene.yaml]
"""

import sys
from pathlib import Path

import numpy as np
import yaml

CENTRED = 0.008
UPRIGHT_COS = np.cos(0.1)


def _columns(signals):
    if isinstance(signals, (str, Path)):
        data = np.genfromtxt(signals, delimiter=",", names=True)
        return {name: data[name] for name in data.dtype.names}
    return getattr(signals, "columns", signals)


def _up_axis_z(qx, qy, qz, qw):
    """z component of the object's own z axis (1 when upright)."""
    return 1.0 - 2.0 * (qx**2 + qy**2)


def done(signals, scene_path) -> bool:
    c = _columns(signals)
    scene = yaml.safe_load(Path(scene_path).read_text())
    objects = {item["name"]: item for item in scene["objects"]}
    frames = scene["frames"]
    # each frame's origin relative to its object's centre (zero in this scene, read all the same)
    block_off = np.subtract(frames["block"]["position"], objects["block"]["position"])
    lower_off = np.subtract(frames["lower"]["position"], objects["lower"]["position"])
    resting_height = objects["block"]["size"][2] + objects["lower"]["size"][2]
    t = np.asarray(c["t"])
    last = t >= t[-1] - 0.5
    block = np.stack([np.asarray(c[f"block_{k}"])[last] for k in "xyz"], axis=1) - block_off
    lower = np.stack([np.asarray(c[f"lower_{k}"])[last] for k in "xyz"], axis=1) - lower_off
    upright = all(np.all(_up_axis_z(*(np.asarray(c[f"{name}_q{k}"])[last] for k in "xyzw")) > UPRIGHT_COS) for name in ("block", "lower"))
    released = np.all(np.asarray(c["block_held"])[last] < 0.5)
    still = max(np.ptp(block, axis=0).max(), np.ptp(lower, axis=0).max()) < 0.002
    centred = np.all(np.abs(block[:, :2] - lower[:, :2]) <= CENTRED)
    resting = np.all(np.abs(block[:, 2] - lower[:, 2] - resting_height) < 0.004)
    return bool(released and still and centred and resting and upright)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else here / "scene.yaml"))
