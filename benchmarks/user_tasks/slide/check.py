"""Was the box physically slid onto the mark? `done(signals, scene_path)` reads the recorded
signals (a mapping of column name to values, or the path of a signals CSV) and the sizes of the
box, the mark and the table from the scene file, not from the spec.

Done means: at the end the box's centre lies over the mark (within the mark's extent), the box
rests flat on the table (its centre at half its height above the table's top, not tipped) and
has stopped, and the fingers never held it.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import yaml


def load_signals(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def geometry(scene_path):
    scene = yaml.safe_load(Path(scene_path).read_text())
    objects = {o["name"]: o for o in scene["objects"]}
    box = objects[scene["frames"]["box"]["objects"][0]]
    mark = objects[scene["frames"]["mark"]["objects"][0]]
    table = objects["table"]
    table_top = table["position"][2] + table["size"][2]
    return np.asarray(box["size"], float), np.asarray(mark["size"], float), float(table_top)


def done(signals, scene_path) -> bool:
    s = load_signals(signals) if isinstance(signals, (str, Path)) else {k: np.asarray(v, dtype=float) for k, v in signals.items()}
    box_half, mark_half, table_top = geometry(scene_path)
    on_mark = abs(s["box_x"][-1] - s["mark_x"][-1]) <= mark_half[0] and abs(s["box_y"][-1] - s["mark_y"][-1]) <= mark_half[1]
    resting = abs(s["box_z"][-1] - (table_top + box_half[2])) < 0.003 and s["box_tilt"][-1] < 0.05
    stopped = s["box_speed"][-1] < 0.005
    never_held = float(np.max(s["box_held"])) < 0.5
    return bool(on_mark and resting and stopped and never_held)


if __name__ == "__main__":
    import sys

    print(done(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else Path(__file__).with_name("scene.yaml")))
