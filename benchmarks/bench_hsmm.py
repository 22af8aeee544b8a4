"""Skill model: learning K = 6 from five 22 s demonstrations at 100 Hz, and one retrieval of a
20 s trajectory at 240 Hz (the optimiser retrieves once per trial); and a skill with
orientation (demos/turn) against the same demonstrations without it, as a ratio."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from benchmarks._timing import Row, median_seconds, print_table
from stl_lfd import QUATERNION_COLUMNS, SignalTable
from stl_lfd.hsmm import learn, learn_from_folder, load_demos, retrieve

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        for path in sorted((ROOT / "demos" / "three_regions").glob("*.csv"))[:5]:
            shutil.copy(path, folder)
        learn_seconds = median_seconds(lambda: learn_from_folder(folder, 6), repeats=3)
        model, _ = learn_from_folder(folder, 6)
    retrieve_seconds = median_seconds(lambda: retrieve(model, duration=20, rate=240), repeats=11)
    print_table(
        "Skill model (HSMM + LQT)",
        [
            Row("learn K = 6", "5 demos x 22 s at 100 Hz", learn_seconds, 2.0, f"{len(model.monitor_.history)} EM iterations"),
            Row("retrieve", "20 s at 240 Hz (4,801 samples)", retrieve_seconds, 0.030, f"model period {model.sample_period_:g} s"),
            *orientation_rows(),
        ],
    )


def orientation_rows() -> list[Row]:
    """Learning and retrieval of demos/turn with its orientation against its positions alone."""
    poses = load_demos(ROOT / "demos" / "turn")
    positions = [
        SignalTable(demo.times, {name: values for name, values in demo.columns.items() if name not in QUATERNION_COLUMNS}, demo.source) for demo in poses
    ]
    learn_pose = median_seconds(lambda: learn(poses, 5), repeats=3)
    learn_position = median_seconds(lambda: learn(positions, 5), repeats=3)
    pose_model, position_model = learn(poses, 5)[0], learn(positions, 5)[0]
    retrieve_pose = median_seconds(lambda: retrieve(pose_model, duration=20, rate=240), repeats=11)
    retrieve_position = median_seconds(lambda: retrieve(position_model, duration=20, rate=240), repeats=11)
    size = "5 demos x 10 s at 50 Hz"
    return [
        Row(
            "learn K = 5, with orientation",
            size,
            learn_pose,
            None,
            f"{learn_pose / learn_position:.1f}x positions only ({len(pose_model.monitor_.history)} EM iterations)",
        ),
        Row("retrieve, with orientation", "20 s at 240 Hz", retrieve_pose, None, f"{retrieve_pose / retrieve_position:.1f}x positions only"),
    ]


if __name__ == "__main__":
    main()
