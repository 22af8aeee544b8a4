"""Is the peg physically in the hole, upright? `done(signals, scene_path)` reads the recorded
signals (a mapping of column name to values, or the path of a signals CSV) and the geometry of
the peg and of the hole from the scene file, not from the spec.

Done means: at the end the peg is let go and still, upright (within 3 degrees), its centre
within the hole's clearance of the axis (the walls' inner faces less the peg's radius, read
from the scene), and its lowest point at least 1 cm below the rim.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import yaml


def load_signals(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def geometry(scene_path):
    """The peg's radius and half length, the hole's clearance, and the rim above the holder frame."""
    scene = yaml.safe_load(Path(scene_path).read_text())
    objects = {o["name"]: o for o in scene["objects"]}
    frames = scene["frames"]
    peg = objects[frames["peg"]["objects"][0]]
    radius, half_length = peg["size"][0], peg["size"][1] / 2
    holder = frames["holder"]
    axis = np.asarray(holder["position"][:2], float)
    inner = min(math.dist(objects[name]["position"][:2], axis) - objects[name]["size"][0] for name in holder["objects"])
    return radius, half_length, inner - radius, float(holder["rim"])


def done(signals, scene_path) -> bool:
    s = load_signals(signals) if isinstance(signals, (str, Path)) else {k: np.asarray(v, dtype=float) for k, v in signals.items()}
    radius, half_length, clearance, rim = geometry(scene_path)
    tilt = s["peg_tilt"][-1]
    offset = math.hypot(s["peg_x"][-1] - s["holder_x"][-1], s["peg_y"][-1] - s["holder_y"][-1])
    bottom = s["peg_z"][-1] - half_length * math.cos(tilt) - radius * math.sin(tilt)
    below_rim = s["holder_z"][-1] + rim - bottom
    upright = tilt < math.radians(3)
    released_and_still = s["peg_held"][-1] < 0.5 and s["peg_speed"][-1] < 0.01
    return bool(upright and released_and_still and offset <= clearance and below_rim >= 0.01)


if __name__ == "__main__":
    import sys

    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else Path(__file__).with_name("scene.yaml")))
