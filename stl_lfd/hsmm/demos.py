"""Demonstrations: a folder of signal CSVs, checked and resampled to one sample period, and
the optional frame sidecars that give the poses of the objects each demonstration refers to."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from stl_lfd.errors import ConfigError, SignalError
from stl_lfd.poses import BASE_FRAME, Pose, parse_pose
from stl_lfd.rotations import QUATERNION_COLUMNS, checked_quaternions
from stl_lfd.signals import SignalTable, read_signal_csv
from stl_lfd.yamlfile import check_keys, read_yaml

POSITION_COLUMNS = ("x", "y", "z")
SIDECAR_SUFFIX = ".frames.yaml"


def load_demos(folder: str | Path) -> list[SignalTable]:
    """Every `*.csv` of `folder`, sorted by name (or `folder` itself, a single demonstration's
    CSV file); each must have `t,x,y,z` and the same columns."""
    folder = Path(folder)
    if folder.is_file() and folder.suffix.lower() == ".csv":
        paths = [folder]
    elif not folder.is_dir():
        raise SignalError(f"{folder}: no such folder of demonstrations (or demonstration CSV file)")
    else:
        paths = sorted(folder.glob("*.csv"))
    if not paths:
        raise SignalError(f"{folder}: no demonstration CSV files in this folder")
    demos = [with_checked_orientation(read_signal_csv(path, required=POSITION_COLUMNS)) for path in paths]
    for demo in demos:
        if demo.samples < 2:
            raise SignalError(f"{demo.source}: a demonstration needs at least 2 samples (found {demo.samples})")
        if list(demo.columns) != list(demos[0].columns):
            raise SignalError(f"{demo.source}: columns {', '.join(demo.columns)} differ from {demos[0].source} ({', '.join(demos[0].columns)})")
    return demos


def demonstration_sets(folder: str | Path) -> list[Path]:
    """The sub-folders of `folder` that hold demonstration CSVs (one set of demonstrations per
    skill, as `demos/` holds them), sorted by name, when `folder` holds no CSV itself; else none."""
    folder = Path(folder)
    if not folder.is_dir() or any(folder.glob("*.csv")):
        return []
    return sorted(path for path in folder.iterdir() if path.is_dir() and any(path.glob("*.csv")))


def with_checked_orientation(demo: SignalTable) -> SignalTable:
    """`demo` with its orientation columns `qx, qy, qz, qw` (if any) checked, normalised and made
    continuous (`rotations.checked_quaternions`); all four or none."""
    present = [name for name in QUATERNION_COLUMNS if name in demo.columns]
    if not present:
        return demo
    if len(present) != 4:
        missing = [name for name in QUATERNION_COLUMNS if name not in demo.columns]
        raise SignalError(f"{demo.source}: the orientation needs all of qx, qy, qz, qw (no column {', '.join(missing)})")
    quaternions = checked_quaternions(np.column_stack([demo.columns[name] for name in QUATERNION_COLUMNS]), demo.source)
    return replace(demo, columns=dict(demo.columns) | dict(zip(QUATERNION_COLUMNS, quaternions.T)))


def median_period(demos: list[SignalTable]) -> float:
    return float(np.median(np.concatenate([np.diff(demo.times) for demo in demos])))


def resample(demo: SignalTable, period: float) -> np.ndarray:
    """`T x D` samples of `demo` every `period` seconds from its first sample (linear
    interpolation; an orientation's quaternions renormalised after it)."""
    times = demo.times[0] + np.arange(int(np.floor(demo.duration / period + 1e-9)) + 1) * period
    samples = np.column_stack([np.interp(times, demo.times, values) for values in demo.columns.values()])
    if all(name in demo.columns for name in QUATERNION_COLUMNS):
        columns = [list(demo.columns).index(name) for name in QUATERNION_COLUMNS]
        samples[:, columns] /= np.linalg.norm(samples[:, columns], axis=1, keepdims=True)
    return samples


def sidecar_path(demo: SignalTable | str | Path) -> Path:
    """`demo_01.frames.yaml` beside `demo_01.csv`."""
    path = Path(demo.source if isinstance(demo, SignalTable) else demo)
    return path.with_name(path.stem + SIDECAR_SUFFIX)


def load_demo_frames(demos: list[SignalTable]) -> list[dict[str, Pose]] | None:
    """The frame poses of every demonstration, from their sidecars; None when no demonstration
    has one. Every demonstration needs a sidecar once one has, with the same frame names."""
    paths = [sidecar_path(demo) for demo in demos]
    present = [path.is_file() for path in paths]
    if not any(present):
        return None
    if not all(present):
        missing, example = paths[present.index(False)], paths[present.index(True)]
        raise ConfigError(f"{missing}: missing; {example.name} gives frames, so every demonstration needs its sidecar")
    frames = [read_sidecar(path) for path in paths]
    for path, poses in zip(paths[1:], frames[1:]):
        if set(poses) != set(frames[0]):
            raise ConfigError(f"{path}: frames {', '.join(sorted(poses))} differ from {paths[0].name} ({', '.join(sorted(frames[0]))})")
    return frames


def read_sidecar(path: Path) -> dict[str, Pose]:
    """`frames: {NAME: {position: [x, y, z], yaw: RAD}}` (base frame, metres, radians)."""
    data = check_keys(read_yaml(path), ("frames",), path, required=("frames",))
    frames = data["frames"]
    if not isinstance(frames, dict) or not frames:
        raise ConfigError(f"{path}: 'frames' must map each object's name to its pose")
    poses = {}
    for name, pose in frames.items():
        if not isinstance(name, str) or not name.isidentifier() or name == BASE_FRAME:
            raise ConfigError(f"{path}: frame name {name!r} must be a name (letters, digits, _) other than '{BASE_FRAME}'")
        poses[name] = parse_pose(pose, path, f"frames.{name}")
    return poses
