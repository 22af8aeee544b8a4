"""The paper's robot task without optimisation: the pick-and-re-orient-and-insert behaviour
learned from the demonstrations without the deliberate error (configs/behaviours/
pick_reorient_insert.yaml), executed on the simulated Panda at 20 object placements it never
saw, drawn by a seeded generator: the shaft and the holder inside the demonstrations' x-y range
or up to 3 cm beyond it, each turned by any yaw.

    python -m benchmarks.bench_reorient [--placements 20] [--seed 20261204] [--backend mujoco]

A placement succeeds when the shaft ends in the hole: its bottom below the holder's top, its
centre within the hole's clearance (6 mm) of the hole's axis in x and y, and upright within 3
degrees. `--demonstrated-yaws` turns the objects only within the demonstrations' yaws.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarks._timing import Row, print_table
from benchmarks.physical import inserted, scene_geometry
from stl_lfd import Pose
from stl_lfd.hsmm import load_demo_frames, load_demos
from stl_lfd.skill import PlacedSkill, placed_scene

ROOT = Path(__file__).resolve().parent.parent
BEHAVIOUR = ROOT / "configs" / "behaviours" / "pick_reorient_insert.yaml"


def placements(count: int, seed: int = 20261204, any_yaw: bool = True) -> list[dict[str, Pose]]:
    """Half inside the demonstrations' x-y range, half up to 3 cm beyond it; any yaws (or the
    demonstrations' range of yaws)."""
    poses = load_demo_frames(load_demos(ROOT / "demos" / "reorient_insert"))
    rng = np.random.default_rng(seed)
    drawn = []
    for index in range(count):
        beyond = 0.03 if index >= count // 2 else 0.0
        placement = {}
        for frame in ("shaft", "holder"):
            xs, ys = [pose[frame].position[0] for pose in poses], [pose[frame].position[1] for pose in poses]
            height = poses[0][frame].position[2]
            position = (rng.uniform(min(xs) - beyond, max(xs) + beyond), rng.uniform(min(ys) - beyond, max(ys) + beyond), height)
            yaws = [pose[frame].yaw for pose in poses]
            placement[frame] = Pose(position, rng.uniform(-np.pi, np.pi) if any_yaw else rng.uniform(min(yaws), max(yaws)))
        drawn.append(placement)
    return drawn


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--placements", type=int, default=20)
    parser.add_argument("--seed", type=int, default=20261204, help="the placements' generator seed")
    parser.add_argument("--demonstrated-yaws", action="store_true", help="turn the objects only within the demonstrations' yaws")
    parser.add_argument("--backend", default="pybullet", help="the simulator")
    parser.add_argument("--nullspace-posture", default=None, help="the arm's nullspace posture, rest or current (default: the scene's)")
    arguments = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    skill = PlacedSkill.load(BEHAVIOUR, duration=36.0)
    if arguments.nullspace_posture is not None:
        control = dataclasses.replace(skill.scene.control, nullspace_posture=arguments.nullspace_posture)
        skill = PlacedSkill(skill.models, skill.behaviour, dataclasses.replace(skill.scene, control=control), 36.0)
    successes, start, notes = 0, time.perf_counter(), []
    for index, placement in enumerate(placements(arguments.placements, arguments.seed, any_yaw=not arguments.demonstrated_yaws), start=1):
        try:
            placed = PlacedSkill(skill.models, skill.behaviour, placed_scene(skill.scene, placement), 36.0)
            ok, how = inserted(placed.execute(arguments.backend, 100).signals, placement["holder"], scene_geometry(skill.behaviour.scene))
        except Exception as error:  # a failed grasp, say: the placement fails
            ok, how = False, str(error)[:60]
        successes += ok
        notes.append(f"{index}: {'in' if ok else 'OUT'} {how}")
    seconds = (time.perf_counter() - start) / arguments.placements
    print("\n".join(notes))
    print_table(
        f"Pick, re-orient and insert, unoptimised ({arguments.backend})",
        [
            Row(
                "shaft in the hole",
                f"{arguments.placements} unseen placements, {'demonstrated' if arguments.demonstrated_yaws else 'any'} yaws, {skill.scene.control.nullspace_posture} posture",
                seconds,
                None,
                f"{successes} of {arguments.placements} (time: per placement)",
            )
        ],
    )


if __name__ == "__main__":
    main()
