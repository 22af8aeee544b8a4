"""Regenerate demos/turn/: demonstrations of a skill with orientation.

The hand moves over three waypoints pointing down, then turns a quarter turn about the base's
x axis (its approach axis from straight down to sideways, along +y) while it moves on, and
holds. Each demonstration has its own timing (segments 10 % longer or shorter), waypoint noise
(3 mm), a constant orientation offset (about 0.6 degrees), and quaternion signs flipped at
random samples, as recorders write them. Sampled at 50 Hz, with columns t,x,y,z,qx,qy,qz,qw.

Run from the repository root: python demos/make_turn.py [--count 5] [--seed 0]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from stl_lfd import rotations
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable, write_signal_csv

ROOT = Path(__file__).resolve().parent.parent
WAYPOINTS = np.array([[0.45, -0.2, 0.4], [0.45, -0.2, 0.4], [0.45, 0.0, 0.3], [0.55, 0.15, 0.35], [0.55, 0.15, 0.25]])
SEGMENT_SECONDS = np.array([2.0, 3.0, 3.0, 2.0])  # hold, move, move while turning, move down


def pose_demos(count: int = 5, seed: int = 0, turn: float = np.pi / 2, axis=(1.0, 0.0, 0.0), rate: float = 50.0) -> list[SignalTable]:
    """`count` demonstrations turning by `turn` radians about `axis` (base frame)."""
    rng = np.random.default_rng(seed)
    demos = []
    for index in range(count):
        durations = SEGMENT_SECONDS * rng.uniform(0.9, 1.1, len(SEGMENT_SECONDS))
        knots = np.concatenate([[0.0], np.cumsum(durations)])
        points = WAYPOINTS + rng.normal(0.0, 0.003, WAYPOINTS.shape)
        times = np.arange(0.0, knots[-1], 1.0 / rate)
        segment = np.clip(np.searchsorted(knots, times, side="right") - 1, 0, len(durations) - 1)
        progress = (times - knots[segment]) / durations[segment]
        progress = progress * progress * (3 - 2 * progress)  # smooth start and stop
        positions = points[segment] + (points[segment + 1] - points[segment]) * progress[:, None]
        angle = np.where(segment < 2, 0.0, np.where(segment == 2, turn * progress, turn))
        offset = rng.normal(0.0, 0.01, 3)
        quaternions = rotations.multiply(rotations.from_rotvec(np.outer(angle, axis) + offset), rotations.DOWN)
        quaternions *= np.where(rng.random(len(times)) < 0.1, -1.0, 1.0)[:, None]
        columns = {"x": positions[:, 0], "y": positions[:, 1], "z": positions[:, 2]} | dict(zip(QUATERNION_COLUMNS, quaternions.T))
        demos.append(SignalTable(times, columns, source=f"generated pose demonstration {index + 1}"))
    return demos


def write_pose_demos(folder: Path, **settings) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("demo_*.csv"):
        old.unlink()
    for index, demo in enumerate(pose_demos(**settings), start=1):
        write_signal_csv(demo, folder / f"demo_{index:02d}.csv")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "demos" / "turn")
    args = parser.parse_args()
    write_pose_demos(args.out, count=args.count, seed=args.seed)


if __name__ == "__main__":
    main()
