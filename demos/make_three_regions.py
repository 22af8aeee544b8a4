"""Regenerate demos/three_regions/: demonstrations of the paper's free-space task.

Each demonstration goes start -> L1 -> L2 -> L3 -> end in about 20 s through the regions of
specs/regions.stl, the way a person guiding the arm would: minimum-jerk segments between
via points, dwell times and segment durations that vary from one demonstration to the next,
points spread around the region centres, a transit from L1 to L2 that passes just outside the
corner of L4 (by a varying amount), and position-sensor noise. Sampled at 100 Hz.

The learned skill therefore visits L1, L2 and L3 and stays in L2 from about 10 to 17 s, but
violates phi1 and phi2: it passes beside L4 around 9 s instead of through it, and (for phi2)
it is in L2 between 12 and 17 s.

Run from the repository root: python demos/make_three_regions.py [--count 6] [--seed 5]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from stl_lfd.signals import SignalTable, write_signal_csv
from stl_lfd.stl import load_spec
from stl_lfd.stl.regions import region_boxes

ROOT = Path(__file__).resolve().parent.parent
RATE_HZ = 100
START = np.array([0.42, 0.0, 0.40])
END = np.array([0.62, 0.08, 0.40])
SENSOR_NOISE_M = 0.0005
END_HOLD_S = 0.5  # rest at the end
# The L1 -> L2 transit passes this point (plus a bow in x), just outside L4's corner.
VIA_X, VIA_Y = 0.445, 0.13


def region_centres() -> dict[str, np.ndarray]:
    boxes = region_boxes(load_spec(ROOT / "specs" / "regions.stl"))
    return {name: np.array([np.mean(box[axis]) for axis in "xyz"]) for name, box in boxes.items()}


def minimum_jerk(times: np.ndarray, waypoints: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """Piecewise minimum-jerk path through `(time, position)` waypoints."""
    positions = np.repeat(waypoints[0][1][None], times.size, axis=0)
    for (t0, p0), (t1, p1) in zip(waypoints[:-1], waypoints[1:]):
        inside = (times >= t0) & (times <= t1)
        phase = (times[inside] - t0) / (t1 - t0)
        blend = 10 * phase**3 - 15 * phase**4 + 6 * phase**5
        positions[inside] = p0 + (p1 - p0) * blend[:, None]
    positions[times > waypoints[-1][0]] = waypoints[-1][1]
    return positions


def demonstration(rng: np.random.Generator, centres: dict[str, np.ndarray]) -> SignalTable:
    def near(point: np.ndarray, spread: float) -> np.ndarray:
        return point + rng.normal(0, spread, size=3) * np.array([1, 1, 0.5])

    def jitter(seconds: float, spread: float) -> float:
        return max(0.3, seconds + rng.normal(0, spread))

    l1, l2, l3 = near(centres["L1"], 0.012), near(centres["L2"], 0.012), near(centres["L3"], 0.012)
    bow = rng.uniform(0.0, 0.01)  # how far the L1 -> L2 transit bows towards L4 (+x)
    via = np.array([VIA_X + bow, VIA_Y + rng.normal(0, 0.01), 0.40 + rng.normal(0, 0.01)])
    phases = [
        ("start", START, jitter(1.2, 0.4)),
        ("to L1", l1, jitter(1.5, 0.3)),
        ("in L1", l1, jitter(3.5, 0.6)),
        ("to via", via, jitter(2.5, 0.3)),
        ("to L2", l2, jitter(1.7, 0.3)),
        ("in L2", l2, jitter(6.0, 0.8)),
        ("to L3", l3, jitter(1.9, 0.3)),
        ("in L3", l3, jitter(1.9, 0.5)),
        ("to end", near(END, 0.005), jitter(1.5, 0.3)),
    ]
    waypoints, clock = [(0.0, near(START, 0.004))], 0.0
    for _, target, seconds in phases:
        clock += seconds
        waypoints.append((clock, target if _ != "start" else waypoints[-1][1]))
    duration = max(20.0, clock + END_HOLD_S)
    times = np.arange(int(round(duration * RATE_HZ)) + 1) / RATE_HZ
    path = minimum_jerk(times, waypoints) + rng.normal(0, SENSOR_NOISE_M, size=(times.size, 3))
    return SignalTable(times, {"x": path[:, 0], "y": path[:, 1], "z": path[:, 2]})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=6)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "demos" / "three_regions")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    centres = region_centres()
    args.out.mkdir(parents=True, exist_ok=True)
    for old in args.out.glob("demo_*.csv"):
        old.unlink()
    for index in range(args.count):
        write_signal_csv(demonstration(rng, centres), args.out / f"demo_{index + 1:02d}.csv")


if __name__ == "__main__":
    main()
