"""Execution: a 20 s rollout of the learned skill in the free-space scene on each backend,
the one-off world set-up, and one video frame (TinyRenderer, 480 x 360)."""

from __future__ import annotations

import time
from pathlib import Path

from benchmarks._timing import Row, median_seconds, print_table
from stl_lfd.hsmm import learn_from_folder
from stl_lfd.sim import execute, load_scene
from stl_lfd.sim.panda import PandaWorld
from stl_lfd.skill.execution import reference_of

ROOT = Path(__file__).resolve().parent.parent
SECONDS = 20.0


def main() -> None:
    model, _ = learn_from_folder(ROOT / "demos" / "three_regions", 6)
    reference = reference_of(model, SECONDS)
    scene = load_scene("free_space")
    start = time.perf_counter()
    world = PandaWorld(scene)
    setup = time.perf_counter() - start
    pybullet_seconds = median_seconds(lambda: execute(reference, scene, "pybullet"), repeats=5)
    kinematic_seconds = median_seconds(lambda: execute(reference, scene, "kinematic"), repeats=11)
    world.reset(reference.positions[0], scene.gripper_opening)
    frame_seconds = median_seconds(lambda: world.render(scene.camera), repeats=5)
    world.close()
    rollout = execute(reference, scene, "pybullet")
    print_table(
        "Execution (free-space scene, 240 Hz simulation, recorded at 100 Hz)",
        [
            Row(
                "pybullet rollout",
                "20 s, 4,800 steps",
                pybullet_seconds,
                1.3,
                f"{SECONDS / pybullet_seconds:.0f}x real time; tracking RMS {1000 * rollout.tracking_rms:.2f} mm",
            ),
            Row("kinematic rollout", "20 s", kinematic_seconds, None),
            Row("pybullet world set-up", "once per process and scene", setup, None),
            Row(
                "video frame",
                f"{scene.camera.width} x {scene.camera.height}",
                frame_seconds,
                None,
                f"{scene.camera.fps:g} fps video: {SECONDS * scene.camera.fps * frame_seconds:.0f} s to film 20 s",
            ),
        ],
    )


if __name__ == "__main__":
    main()
