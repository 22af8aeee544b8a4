"""Regenerate demos/pick_lying/ and demos/reorient_insert/: demonstrations of the paper's robot
task, picking a shaft that lies on its side, turning it upright and inserting it into a holder,
each with the shaft and the holder at another pose, recorded in a frame sidecar beside it.

pick_lying: from the home pose (hand pointing down), over a via point to above the shaft while
the hand turns about the vertical so that its fingers close across the shaft, then down to the
grasp pose at the shaft's centre. Sidecar: the shaft's pose.
reorient_insert: from the grasp pose, lift, carry towards the holder while turning the hand a
quarter turn about the horizontal axis across the shaft (the shaft comes upright, the hand
points sideways) and to the same heading relative to the holder every time, hover over the
hole, lower the shaft into it and stop. Sidecar: the poses of
the shaft (where it was grasped) and of the holder.

Placements: demonstration i moves the shaft and the holder from the scene's default poses by
offsets spread over +-8 cm in x and y (stratified), and turns each by a yaw spread over +-30
degrees likewise. Minimum-jerk segments, varying timing and via points, 0.5 mm and 0.3 degree
sensor noise, 100 Hz; columns t,x,y,z,qx,qy,qz,qw.
With `--shift-mm S --turn-deg A --insert-folder reorient_insert_off`, the insertion stops S mm
off the hole's centre along the holder's x axis and the hand turns by A degrees instead of 90:
the realistic error (a shift between hand and holder, a shaft not quite upright) that
configs/phi3_reorient.yaml asks the optimiser to correct.

Run from the repository root: python demos/make_pick_reorient_insert.py [--count 6] [--seed 7]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from stl_lfd import rotations
from stl_lfd.poses import Pose
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable, write_signal_csv

ROOT = Path(__file__).resolve().parent.parent
RATE_HZ = 100
SENSOR_NOISE_M, SENSOR_NOISE_RAD = 0.0005, np.radians(0.3)
HOME = np.array([0.42, 0.0, 0.40])
# The pick_reorient_insert scene's default frames: the lying shaft's centre and the hole's centre.
SHAFT = Pose((0.45, -0.25, 0.056))
HOLDER = Pose((0.55, 0.20, 0.04))
SHAFT_HALF_LENGTH = 0.06
HOLE_BOTTOM_IN_HOLDER = -0.015  # the upright shaft's bottom 5 mm above the table inside the holder
PLACEMENT_SPREAD_M, YAW_SPREAD = 0.08, np.radians(30.0)
STOP_SPREAD_M, TURN_SPREAD_DEG = 0.004, 3.0  # how far the demonstrated insertions differ
# The hand's orientation in the shaft's frame: pointing down, turned so that the fingers close
# across the shaft (which lies along the frame's y axis); and after the quarter turn about the
# frame's x axis, which brings the shaft upright.
GRASPING = rotations.multiply(rotations.from_yaw(np.pi / 2), rotations.DOWN)


def turned(degrees: float) -> np.ndarray:
    """The hand in the shaft's frame after turning by `degrees` about the frame's x axis."""
    return rotations.multiply(rotations.from_rotvec([np.radians(degrees), 0.0, 0.0]), GRASPING)


def stratified(rng: np.random.Generator, count: int, spread: float) -> np.ndarray:
    """`count` values over [-spread, spread], one in each of `count` equal slices, shuffled."""
    return rng.permutation((np.arange(count) + rng.uniform(size=count)) / count * 2 * spread - spread)


def placements(rng: np.random.Generator, count: int) -> list[dict[str, Pose]]:
    """Per demonstration: the poses of the shaft and the holder."""
    offsets = [stratified(rng, count, PLACEMENT_SPREAD_M) for _ in range(4)]
    yaws = [stratified(rng, count, YAW_SPREAD) for _ in range(2)]
    return [
        {
            "shaft": Pose((SHAFT.position[0] + offsets[0][i], SHAFT.position[1] + offsets[1][i], SHAFT.position[2]), float(yaws[0][i])),
            "holder": Pose((HOLDER.position[0] + offsets[2][i], HOLDER.position[1] + offsets[3][i], HOLDER.position[2]), float(yaws[1][i])),
        }
        for i in range(count)
    ]


def minimum_jerk(times: np.ndarray, knots: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """The segment each time falls in and its minimum-jerk progress (0 to 1)."""
    knots = np.asarray(knots)
    segment = np.clip(np.searchsorted(knots, times, side="right") - 1, 0, len(knots) - 2)
    phase = np.clip((times - knots[segment]) / (knots[segment + 1] - knots[segment]), 0.0, 1.0)
    return segment, 10 * phase**3 - 15 * phase**4 + 6 * phase**5


def demonstration(rng: np.random.Generator, phases: list[tuple[np.ndarray, np.ndarray, float, float]], hold_end: float) -> SignalTable:
    """Poses (position, quaternion) reached after each phase of (mean seconds, spread), then a
    final hold; orientations interpolated along the geodesic between consecutive poses."""
    knots = [0.0]
    for _, _, seconds, spread in phases[1:]:
        knots.append(knots[-1] + max(0.3, seconds + rng.normal(0, spread)))
    times = np.arange(int(round((knots[-1] + hold_end) * RATE_HZ)) + 1) / RATE_HZ
    segment, progress = minimum_jerk(times, knots)
    positions = np.array([phase[0] for phase in phases])
    turns = np.array([phase[1] for phase in phases])
    path = positions[segment] + (positions[segment + 1] - positions[segment]) * progress[:, None]
    steps = rotations.log_map(turns[segment], turns[segment + 1]) * progress[:, None]
    quaternions = rotations.exp_map(turns[segment], steps + rng.normal(0, SENSOR_NOISE_RAD, size=steps.shape))
    path += rng.normal(0, SENSOR_NOISE_M, size=path.shape)
    columns = {"x": path[:, 0], "y": path[:, 1], "z": path[:, 2]} | dict(zip(QUATERNION_COLUMNS, quaternions.T))
    return SignalTable(times, columns)


def in_base(pose: Pose, position, orientation) -> tuple[np.ndarray, np.ndarray]:
    return pose.to_base(np.asarray(position, dtype=float)[None])[0], rotations.multiply(pose.orientation, orientation)


def pick(rng: np.random.Generator, poses: dict[str, Pose]) -> SignalTable:
    shaft = poses["shaft"]
    grasp = in_base(shaft, [0.0, 0.0, 0.0], GRASPING)
    above = (grasp[0] + [0.0, 0.0, 0.15] + rng.normal(0, 0.004, 3) * [1, 1, 0.5], grasp[1])
    via = np.array([0.35, -0.10, 0.45]) + rng.normal(0, 0.015, 3) * [1, 1, 0.5]
    phases = [
        (HOME, rotations.DOWN, 0.0, 0.0),
        (HOME, rotations.DOWN, 2.5, 0.4),  # wait at home
        (via, rotations.multiply(rotations.from_yaw(0.5 * (shaft.yaw + np.pi / 2)), rotations.DOWN), 4.0, 0.5),
        (*above, 4.0, 0.5),
        (grasp[0] + rng.normal(0, 0.001, 3), grasp[1], 3.5, 0.4),
    ]
    return demonstration(rng, phases, hold_end=2.5)


def reorient_insert(rng: np.random.Generator, poses: dict[str, Pose], shift: float = 0.0, turn_degrees: float = 90.0) -> SignalTable:
    shaft, holder = poses["shaft"], poses["holder"]
    grasp = in_base(shaft, [0.0, 0.0, 0.0], GRASPING)
    lifted = in_base(shaft, [0.0, 0.0, 0.12], GRASPING)
    # People neither turn by the same angle nor stop at the same point twice: this spread sets
    # the bounds of the insertion's optimisation.
    # The hand ends facing the holder as always (its heading relative to the holder), the shaft upright.
    upright = rotations.multiply(holder.orientation, turned(turn_degrees + rng.normal(0, TURN_SPREAD_DEG)))
    off = np.append(rng.normal(0, STOP_SPREAD_M, 2) + [shift, 0.0], HOLE_BOTTOM_IN_HOLDER + SHAFT_HALF_LENGTH)
    stop = holder.to_base(off[None])[0] + rng.normal(0, 0.0005, 3)
    hover = stop + [0.0, 0.0, 0.10] + rng.normal(0, 0.002, 3) * [1, 1, 0.3]
    midway = 0.5 * (lifted[0] + hover) + [0.0, 0.0, 0.05] + rng.normal(0, 0.01, 3) * [1, 1, 0.3]
    phases = [
        (*grasp, 0.0, 0.0),
        (*grasp, 1.5, 0.2),
        (*lifted, 2.0, 0.3),
        (midway, rotations.weighted_mean(np.array([grasp[1], upright])), 2.5, 0.3),
        (hover, upright, 2.5, 0.3),
        (hover, upright, 1.5, 0.2),  # steady above the hole, then straight down
        (stop, upright, 1.5, 0.2),
    ]
    return demonstration(rng, phases, hold_end=2.0)


def write_sidecar(path: Path, poses: dict[str, Pose]) -> None:
    frames = {name: {"position": [round(float(v), 6) for v in pose.position], "yaw": round(float(pose.yaw), 6)} for name, pose in poses.items()}
    path.write_text(yaml.safe_dump({"frames": frames}, default_flow_style=None, sort_keys=False))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=6)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--out", type=Path, default=ROOT / "demos")
    parser.add_argument("--shift-mm", type=float, default=0.0, help="the insertion's stop off the hole's centre along the holder's x axis")
    parser.add_argument("--turn-deg", type=float, default=90.0, help="how far the hand turns the shaft (90: upright)")
    parser.add_argument("--insert-folder", default="reorient_insert", help="the folder of the insertion's demonstrations")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    for name in ("pick_lying", args.insert_folder):
        (args.out / name).mkdir(parents=True, exist_ok=True)
        for old in (args.out / name).glob("demo_*"):
            old.unlink()
    for index, poses in enumerate(placements(rng, args.count), start=1):
        stem = f"demo_{index:02d}"
        write_signal_csv(pick(rng, poses), args.out / "pick_lying" / f"{stem}.csv")
        write_sidecar(args.out / "pick_lying" / f"{stem}.frames.yaml", {"shaft": poses["shaft"]})
        write_signal_csv(reorient_insert(rng, poses, args.shift_mm / 1000, args.turn_deg), args.out / args.insert_folder / f"{stem}.csv")
        write_sidecar(args.out / args.insert_folder / f"{stem}.frames.yaml", poses)


if __name__ == "__main__":
    main()
