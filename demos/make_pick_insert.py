"""Regenerate demos/pick/ and demos/insert/: demonstrations of the pick-and-insert behaviour,
each with the shaft and the holder at another pose, recorded in a frame sidecar beside it.

pick: from the home pose, a slow, roundabout path (via two points above the table, as a
person guiding the arm might take) to above the shaft, then down to the grasp pose, in about
26 s; so the learned pick reaches the shaft after 20 s. Sidecar: the shaft's pose.
insert: from the grasp pose, lift, carry to above the holder, hover, descend straight and stop;
the demonstrated stop is 8 mm off the hole's centre along the holder's x axis (the paper's
shift between end effector and holder), so the learned insertion pushes the shaft onto the
holder's edge. Sidecar: the poses of the shaft (where it was grasped) and of the holder.

Placements: demonstration i moves the shaft and the holder from the scene's default poses by
offsets spread over +-8 cm in x and y (stratified: each coordinate's range is cut into as many
slices as there are demonstrations, one offset per slice, slices shuffled independently), and
turns the holder by a yaw spread over +-30 degrees likewise. The shaft is a cylinder: its
yaw is recorded as 0.

Both: minimum-jerk segments, varying timing and via points, 0.5 mm sensor noise, 100 Hz.
Run from the repository root: python demos/make_pick_insert.py [--count 6] [--seed 11] [--shift-mm 8]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable, write_signal_csv

ROOT = Path(__file__).resolve().parent.parent
RATE_HZ = 100
SENSOR_NOISE_M = 0.0005
HOME = np.array([0.42, 0.0, 0.40])
# The pick_insert scene's default frames: the shaft's centre and the holder's hole centre.
SHAFT = Pose((0.45, -0.25, 0.08))
HOLDER = Pose((0.55, 0.20, 0.04))
GRASP_IN_SHAFT = np.array([0.0, 0.0, 0.03])  # the grasp-target link around the shaft
HOLE_IN_HOLDER = np.array([0.0, 0.0, 0.075])  # shaft bottom 5 mm above the table inside the holder
PLACEMENT_SPREAD_M = 0.08
YAW_SPREAD = np.radians(30.0)
# Where each demonstration stops around the shifted hole (mm in the holder's x, y, z): people
# do not stop at the same point twice, and this spread sets the bounds of the insertion's
# optimisation.
STOP_SPREAD_MM = [(-6, 4, 3), (5, -5, -2), (0, 0, 5), (-3, -6, 0), (4, 6, 8), (-2, 5, -3)]


def stratified(rng: np.random.Generator, count: int, spread: float) -> np.ndarray:
    """`count` values over [-spread, spread], one in each of `count` equal slices, shuffled."""
    return rng.permutation((np.arange(count) + rng.uniform(size=count)) / count * 2 * spread - spread)


def placements(rng: np.random.Generator, count: int) -> list[dict[str, Pose]]:
    """Per demonstration: the poses of the shaft and the holder."""
    shaft_x, shaft_y, holder_x, holder_y = (stratified(rng, count, PLACEMENT_SPREAD_M) for _ in range(4))
    yaws = stratified(rng, count, YAW_SPREAD)
    return [
        {
            "shaft": Pose((SHAFT.position[0] + shaft_x[i], SHAFT.position[1] + shaft_y[i], SHAFT.position[2])),
            "holder": Pose((HOLDER.position[0] + holder_x[i], HOLDER.position[1] + holder_y[i], HOLDER.position[2]), float(yaws[i])),
        }
        for i in range(count)
    ]


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


def demonstration(rng: np.random.Generator, phases: list[tuple[np.ndarray, float, float]], hold_end: float) -> SignalTable:
    """Waypoints reached after each (target, mean seconds, spread) phase, then a final hold."""
    waypoints, clock = [(0.0, phases[0][0])], 0.0
    for target, seconds, spread in phases[1:]:
        clock += max(0.3, seconds + rng.normal(0, spread))
        waypoints.append((clock, target))
    times = np.arange(int(round((clock + hold_end) * RATE_HZ)) + 1) / RATE_HZ
    path = minimum_jerk(times, waypoints) + rng.normal(0, SENSOR_NOISE_M, size=(times.size, 3))
    return SignalTable(times, {"x": path[:, 0], "y": path[:, 1], "z": path[:, 2]})


def pick(rng: np.random.Generator, poses: dict[str, Pose]) -> SignalTable:
    def near(point, spread):
        return np.asarray(point) + rng.normal(0, spread, size=3) * np.array([1, 1, 0.5])

    grasp = poses["shaft"].to_base(GRASP_IN_SHAFT[None])[0]
    above = grasp + np.array([0.0, 0.0, 0.14])
    phases = [
        (HOME, 0.0, 0.0),
        (HOME, 3.5, 0.5),  # wait at home
        (near([0.30, 0.10, 0.50], 0.015), 5.0, 0.6),
        (near([0.28, -0.20, 0.50], 0.015), 5.0, 0.6),
        (near(above, 0.004), 5.0, 0.6),
        (grasp + rng.normal(0, 0.001, 3), 4.0, 0.5),
    ]
    return demonstration(rng, phases, hold_end=3.0)


def insert(rng: np.random.Generator, poses: dict[str, Pose], index: int, shift: np.ndarray) -> SignalTable:
    def near(point, spread):
        return np.asarray(point) + rng.normal(0, spread, size=3) * np.array([1, 1, 0.3])

    grasp = poses["shaft"].to_base(GRASP_IN_SHAFT[None])[0]
    lifted = grasp + np.array([0.0, 0.0, 0.14])
    stop_in_holder = HOLE_IN_HOLDER + shift + np.array(STOP_SPREAD_MM[index % len(STOP_SPREAD_MM)]) / 1000
    stop = poses["holder"].to_base(stop_in_holder[None])[0]
    hover = near(stop + np.array([0, 0, 0.19]), 0.002)
    phases = [
        (grasp, 0.0, 0.0),
        (grasp, 2.5, 0.3),
        (near(lifted, 0.003), 2.5, 0.3),
        (near([0.52, -0.02, 0.27], 0.01), 3.0, 0.4),
        (hover, 3.0, 0.4),
        (hover, 2.0, 0.3),  # steady above the holder, then straight down
        (stop, 0.8, 0.1),
    ]
    return demonstration(rng, phases, hold_end=2.5)


def write_sidecar(path: Path, poses: dict[str, Pose]) -> None:
    frames = {name: {"position": [round(float(v), 6) for v in pose.position], "yaw": round(float(pose.yaw), 6)} for name, pose in poses.items()}
    path.write_text(yaml.safe_dump({"frames": frames}, default_flow_style=None, sort_keys=False))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=6)
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--out", type=Path, default=ROOT / "demos")
    parser.add_argument("--shift-mm", type=float, default=8.0, help="demonstrated insertion offset from the hole along the holder's x axis")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    shift = np.array([args.shift_mm / 1000, 0.0, 0.0])
    scenes = placements(rng, args.count)
    for name in ("pick", "insert"):
        folder = args.out / name
        folder.mkdir(parents=True, exist_ok=True)
        for old in [*folder.glob("demo_*.csv"), *folder.glob("demo_*.frames.yaml")]:
            old.unlink()
    for index, poses in enumerate(scenes):
        stem = f"demo_{index + 1:02d}"
        write_signal_csv(pick(rng, poses), args.out / "pick" / f"{stem}.csv")
        write_sidecar(args.out / "pick" / f"{stem}.frames.yaml", {"shaft": poses["shaft"]})
        write_signal_csv(insert(rng, poses, index, shift), args.out / "insert" / f"{stem}.csv")
        write_sidecar(args.out / "insert" / f"{stem}.frames.yaml", poses)


if __name__ == "__main__":
    main()
