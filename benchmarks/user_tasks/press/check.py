"""Was the button physically pressed? `done(signals, scene_path)` reads the recorded signals
(a mapping of column name to values, `t` included, or the path of a signals CSV) and the
button's size from the scene file, not from the spec.

Pressed means: while the hand is over the button's top face, the measured contact force stays
between 3 and 8 N for at least 2 s in one go, it never exceeds 8 N, and afterwards the hand
is lifted clear of the button (at least 5 cm above its top, touching nothing) at the end.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import yaml

LOW_N, HIGH_N, HOLD_S = 3.0, 8.0, 2.0
CLEAR_M, FREE_N = 0.05, 0.5


def load_signals(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def button_geometry(scene_path) -> tuple[np.ndarray, float]:
    """The button's half extents (x, y) and its top's height above the button frame's origin."""
    scene = yaml.safe_load(Path(scene_path).read_text())
    frame = scene["frames"]["button"]
    body = next(o for o in scene["objects"] if o["name"] == frame["objects"][0])
    half = np.asarray(body["size"], dtype=float)
    top = body["position"][2] + half[2] - frame["position"][2]
    return half[:2], float(top)


def longest_run(times: np.ndarray, mask: np.ndarray) -> float:
    best, start = 0.0, None
    for i, inside in enumerate(mask):
        if inside and start is None:
            start = i
        if start is not None and (not inside or i == len(mask) - 1):
            end = i if inside else i - 1
            best = max(best, times[end] - times[start])
            start = None
    return best


def done(signals, scene_path) -> bool:
    s = load_signals(signals) if isinstance(signals, (str, Path)) else {k: np.asarray(v, dtype=float) for k, v in signals.items()}
    half, top_offset = button_geometry(scene_path)
    t, force = s["t"], s["force"]
    top = s["button_z"] + top_offset
    over = (np.abs(s["x"] - s["button_x"]) <= half[0]) & (np.abs(s["y"] - s["button_y"]) <= half[1]) & (s["z"] - top < 0.02)
    in_band = over & (force >= LOW_N) & (force <= HIGH_N)
    held_long_enough = longest_run(t, in_band) >= HOLD_S
    never_too_hard = bool(np.all(force[over] <= HIGH_N))
    retreated = s["z"][-1] - top[-1] >= CLEAR_M and force[-1] < FREE_N
    return bool(held_long_enough and never_too_hard and retreated)


if __name__ == "__main__":
    import sys

    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else Path(__file__).with_name("scene.yaml")))
