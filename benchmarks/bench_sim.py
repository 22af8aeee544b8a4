"""Execution: a 20 s rollout of the learned skill in the free-space scene on each backend,
measured in one process so that the ratios compare like with like; the one-off world set-up;
one video frame of each simulator (480 x 360).

    python -m benchmarks.bench_sim

The issue's target: a MuJoCo rollout of phi1's skill at least 20x real time on one core (the
row's limit is 20 s / 20); PyBullet's figure beside it.
"""

from __future__ import annotations

import time
from pathlib import Path

from benchmarks._timing import Row, median_seconds, print_table
from stl_lfd.hsmm import learn_from_folder
from stl_lfd.sim import execute, load_scene, new_backend
from stl_lfd.skill import build_reference

ROOT = Path(__file__).resolve().parent.parent
SECONDS = 20.0
REAL_TIME_FACTOR = 20.0  # the simulators' target: at least this many times real time


def main() -> None:
    model, _ = learn_from_folder(ROOT / "demos" / "three_regions", 6)
    reference = build_reference({"skill": model}, duration=SECONDS)
    scene = load_scene("free_space")
    rows = []
    for engine in ("mujoco", "pybullet"):
        with new_backend(engine) as backend:
            start = time.perf_counter()
            world = backend.world(scene)
            setup = time.perf_counter() - start
            rollout = execute(reference, scene, backend)
            seconds = median_seconds(lambda: execute(reference, scene, backend), repeats=5)
            frame = median_seconds(lambda: world.render(scene.camera), repeats=3)
        target = SECONDS / REAL_TIME_FACTOR if engine == "mujoco" else None
        rows += [
            Row(
                f"{engine} rollout",
                "20 s, 4,800 control steps",
                seconds,
                target,
                f"{SECONDS / seconds:.0f}x real time; tracking RMS {1000 * rollout.tracking_rms:.2f} mm, force max {rollout.signals.columns['force'].max():.2f} N",
            ),
            Row(f"{engine} world set-up", "once per process and scene", setup, None),
            Row(
                f"{engine} video frame",
                f"{scene.camera.width} x {scene.camera.height}",
                frame,
                None,
                f"{SECONDS * scene.camera.fps * frame:.0f} s to film 20 s",
            ),
        ]
    rows.append(Row("kinematic rollout", "20 s", median_seconds(lambda: execute(reference, scene, "kinematic"), repeats=11), None))
    print_table("Execution (free-space scene, 240 Hz control, recorded at 100 Hz)", rows)


if __name__ == "__main__":
    main()
