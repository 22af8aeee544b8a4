"""Where retrieved skills end: the distance from the retrieval's end point to the
demonstrations' mean end point, in % of the figure's extent (the largest side of the box
around all demonstrated samples), on the bundled demonstrations and on generated planar
handwriting-like shapes (five demonstrations each, K = 8, three generator seeds, the worst
reported).

TP-HSMM skills are measured in the frame that holds their end (the shaft for the pick, the
holder for the insert): retrieved at each demonstration's frame poses, their end expressed in
that frame, against the demonstrations' mean end in it; the worst demonstration is reported.

    python -m benchmarks.bench_endpoint
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from stl_lfd import SignalTable
from stl_lfd.hsmm import learn, load_demo_frames, load_demos, retrieve

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ("sine", "spiral", "arc", "zigzag", "hook")


def shape(name: str, progress: np.ndarray) -> np.ndarray:
    """`T x 2` points of a planar figure at path parameters `progress` in [0, 1]."""
    s = progress
    if name == "sine":
        return np.column_stack([s, 0.3 * np.sin(2 * np.pi * s)])
    if name == "spiral":
        radius, angle = 1 - 0.8 * s, 3 * np.pi * s
        return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    if name == "arc":
        return np.column_stack([np.cos(1.5 * np.pi * s), np.sin(1.5 * np.pi * s)])
    if name == "zigzag":
        corners = np.array([[0, 0], [0.25, 0.5], [0.5, 0], [0.75, 0.5], [1, 0]])
        leg = np.minimum((s * 4).astype(int), 3)
        fraction = (s * 4 - leg)[:, None]
        return corners[leg] * (1 - fraction) + corners[leg + 1] * fraction
    return np.column_stack([np.sin(np.pi * s), 1 - s**2])  # hook


def shape_demos(name: str, count: int = 5, seed: int = 0) -> list[SignalTable]:
    """Demonstrations of a figure: 3-4 s, minimum-jerk timing with a varying pace, a varying
    scale and start, the same end (2 mm spread), 1 mm noise, 100 Hz; they slow to a stop."""
    rng = np.random.default_rng(seed)
    demos = []
    for index in range(count):
        seconds = rng.uniform(3, 4)
        times = np.arange(0, seconds + 1e-9, 0.01)
        phase = times / seconds
        progress = (10 * phase**3 - 15 * phase**4 + 6 * phase**5) ** rng.uniform(0.85, 1.15)
        points = shape(name, progress) * rng.uniform(0.95, 1.05) + (1 - progress)[:, None] * rng.normal(0, 0.02, 2)
        points += shape(name, np.ones(1))[0] - points[-1] + rng.normal(0, 0.002, 2)
        points += rng.normal(0, 0.001, points.shape)
        demos.append(SignalTable(times, {"x": points[:, 0], "y": points[:, 1]}, f"{name}-{index}"))
    return demos


def end_error(demos: list[SignalTable], states: int, end_frame: str | None = None) -> float:
    """The retrieval's end point's distance to the demonstrations' mean end, % of the extent."""
    poses = load_demo_frames(demos) if end_frame is not None else None
    frames = ["base", *poses[0]] if poses else None
    model, sequences = learn(demos, states, poses=poses, frames=frames)
    extent = np.ptp(np.concatenate(sequences), axis=0).max()
    if poses is None:
        mean_end = np.mean([sequence[-1] for sequence in sequences], axis=0)
        return float(np.linalg.norm(retrieve(model).positions[-1] - mean_end) / extent * 100)
    local_ends = np.array([pose[end_frame].from_base(sequence[-1:, :3])[0] for sequence, pose in zip(sequences, poses)])
    errors = [np.linalg.norm(pose[end_frame].from_base(retrieve(model, poses=pose).positions[-1:, :3])[0] - local_ends.mean(axis=0)) for pose in poses]
    return float(max(errors) / extent * 100)


def main() -> None:
    table = Table(title="retrieval end point: distance to the demonstrations' mean end (% of the figure's extent)")
    for column in ("demonstrations", "K", "frame of the end", "end error"):
        table.add_column(column)
    table.add_row("demos/three_regions", "6", "base", f"{end_error(load_demos(ROOT / 'demos' / 'three_regions'), 6):.2f} %")
    for folder, frame in (("pick", "shaft"), ("insert", "holder")):
        table.add_row(f"demos/{folder} (TP-HSMM)", "6", frame, f"{end_error(load_demos(ROOT / 'demos' / folder), 6, frame):.2f} %")
    for name in SHAPES:
        worst = max(end_error(shape_demos(name, seed=seed), 8) for seed in range(3))
        table.add_row(f"planar {name}", "8", "base", f"{worst:.2f} %")
    Console().print(table)


if __name__ == "__main__":
    main()
