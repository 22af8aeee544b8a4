"""Regenerate the example signals in this folder (deterministic).

- s1.csv, s2.csv: the two 1-D signals of the paper's introductory example (specs/example.stl):
  S1 satisfies it with classic robustness 0.1, S2 violates it with -0.05.
- three_regions.csv: a 20 s end-effector path start -> L1 -> L2 -> L3 -> end through the
  regions of specs/regions.stl, as the demonstrations do; it violates phi1 and phi2.

Run from the repository root: python examples/make_examples.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stl_lfd.signals import SignalTable, write_signal_csv
from stl_lfd.stl import load_spec
from stl_lfd.stl.regions import region_boxes

HERE = Path(__file__).resolve().parent
RATE_HZ = 100


def minimum_jerk(times: np.ndarray, waypoints: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """Piecewise minimum-jerk path through `(time, position)` waypoints; holds between equal ones."""
    positions = np.empty((times.size, waypoints[0][1].size))
    for (t0, p0), (t1, p1) in zip(waypoints[:-1], waypoints[1:]):
        inside = (times >= t0) & (times <= t1)
        phase = (times[inside] - t0) / (t1 - t0)
        blend = 10 * phase**3 - 15 * phase**4 + 6 * phase**5
        positions[inside] = p0 + (p1 - p0) * blend[:, None]
    return positions


def one_dimensional(levels: list[tuple[float, float]]) -> SignalTable:
    times = np.round(np.arange(0, int(8.5 * RATE_HZ) + 1) / RATE_HZ, 10)
    path = minimum_jerk(times, [(t, np.array([s])) for t, s in levels])
    return SignalTable(times, {"s": path[:, 0]})


def three_regions() -> SignalTable:
    boxes = region_boxes(load_spec(HERE.parent / "specs" / "regions.stl"))
    centre = {name: np.array([np.mean(box[axis]) for axis in "xyz"]) for name, box in boxes.items()}
    start, end = np.array([0.45, 0.0, 0.40]), np.array([0.62, 0.06, 0.40])
    waypoints = [
        (0.0, start),
        (1.0, start),
        (3.5, centre["L1"]),
        (5.0, centre["L1"]),
        (8.5, centre["L2"]),
        (10.5, centre["L2"]),
        (14.5, centre["L3"]),
        (16.0, centre["L3"]),
        (18.5, end),
        (20.0, end),
    ]
    times = np.round(np.arange(0, 20 * RATE_HZ + 1) / RATE_HZ, 10)
    path = minimum_jerk(times, waypoints)
    return SignalTable(times, {"x": path[:, 0], "y": path[:, 1], "z": path[:, 2]})


def main() -> None:
    write_signal_csv(one_dimensional([(0, 0.25), (1, 0.25), (3, 0.5), (3.2, 0.5), (6, 0.35), (8.5, 0.35)]), HERE / "s1.csv")
    write_signal_csv(one_dimensional([(0, 0.25), (1, 0.25), (3, 0.5), (3.2, 0.5), (6, 0.15), (8.5, 0.3)]), HERE / "s2.csv")
    write_signal_csv(three_regions(), HERE / "three_regions.csv")


if __name__ == "__main__":
    main()
