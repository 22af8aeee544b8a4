"""Learning a skill model from a folder of demonstrations, and its summary."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm.demos import SIDECAR_SUFFIX, load_demo_frames, load_demos, median_period, resample
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.spread import ONE_DEMONSTRATION, MinimumSpread
from stl_lfd.hsmm.tp import TPHSMM
from stl_lfd.limits import MAX_STATES, samples_problem
from stl_lfd.poses import BASE_FRAME, Pose, parse_assignment
from stl_lfd.signals import SignalTable
from stl_lfd.spelling import spelled

# Demonstrations are resampled no finer than this (s): hand-guided motions have no content
# above a few hertz, and EM, state sequences and tracking all cost time per sample.
COARSEST_DEFAULT_PERIOD = 0.02


def learn_from_folder(
    folder: str | Path,
    n_states: int = 6,
    sample_period: float | None = None,
    frames: list[str] | None = None,
    restarts: int = 1,
    min_spread: MinimumSpread | None | str = "auto",
) -> tuple[HSMM, list[np.ndarray]]:
    """Load every demonstration CSV of `folder` and its frame sidecar if any, then `learn`.

    With sidecars the model is a `TPHSMM` in the frames `frames` (default: `base` and every
    frame of the sidecars); `frames=["base"]` without sidecars gives a one-frame `TPHSMM`.
    """
    _check_settings(n_states, sample_period)
    demos = load_demos(folder)
    poses = load_demo_frames(demos)
    frames = model_frames(poses, frames, str(folder))
    return learn(demos, n_states, sample_period, source=str(folder), poses=poses, frames=frames, restarts=restarts, min_spread=min_spread)


def model_frames(poses: list[dict[str, Pose]] | None, chosen: list[str] | None, source: str) -> list[str] | None:
    """The frames to learn in: `chosen` (checked against the sidecars), or `base` and every
    sidecar frame, or None (a plain HSMM) without sidecars."""
    available = [BASE_FRAME] + (list(poses[0]) if poses else [])
    if chosen is None:
        return available if poses else None
    unknown = [name for name in chosen if name not in available]
    if unknown:
        where = f"the sidecars give {', '.join(available[1:])}" if poses else f"no demonstration has a frame sidecar (*{SIDECAR_SUFFIX})"
        raise ModelError(f"{source}: no frame {', '.join(unknown)} ({where})")
    return list(chosen)  # distinct and not empty: `TPHSMM.fit` checks


def learn(
    demos: list[SignalTable],
    n_states: int = 6,
    sample_period: float | None = None,
    source: str = "demonstrations",
    poses: list[dict[str, Pose]] | None = None,
    frames: list[str] | None = None,
    restarts: int = 1,
    min_spread: MinimumSpread | None | str = "auto",
) -> tuple[HSMM, list[np.ndarray]]:
    """Resample the demonstrations (signal tables with the same columns) to one period and fit
    (`restarts` EM starts, the most likely kept: `HSMM.n_init`).

    `min_spread` floors the learned spread (`HSMM.min_spread`); "auto" floors it at
    `ONE_DEMONSTRATION` when there is a single demonstration, and not at all otherwise.

    The default period is the demonstrations' median period, but not finer than
    `COARSEST_DEFAULT_PERIOD` (50 Hz). With `frames`, the model is a `TPHSMM` learned in those
    frames, `poses` giving each demonstration's frame poses.

    Returns:
        the fitted model and the resampled demonstrations (`T_i x D` each, base frame).
    """
    _check_settings(n_states, sample_period)
    if not demos:
        raise ModelError(f"{source}: no demonstrations to learn from")
    period = learning_period(demos, sample_period)
    longest = max(demos, key=lambda demo: demo.duration)
    problem = samples_problem(longest.duration, 1.0 / period)
    if problem:
        raise ModelError(f"{longest.source}: cannot resample to a period of {period:g} s: {problem}")
    sequences = [resample(demo, period) for demo in demos]
    shortest = min(len(sequence) for sequence in sequences)
    if shortest < 2 * n_states:
        raise ModelError(
            f"{source}: K = {n_states} needs at least {2 * n_states} samples per demonstration (the shortest has {shortest} after resampling); use a smaller K"
        )
    lengths = np.array([len(s) for s in sequences])
    if min_spread == "auto":
        min_spread = ONE_DEMONSTRATION if len(demos) == 1 else None
    assert not isinstance(min_spread, str)
    if frames is None:
        return HSMM(n_states=n_states, n_init=restarts, min_spread=min_spread).fit(
            np.concatenate(sequences), lengths, period, list(demos[0].columns)
        ), sequences
    poses = poses if poses is not None else [{} for _ in demos]
    model = TPHSMM(n_states=n_states, n_init=restarts, min_spread=min_spread)
    try:
        model.fit(np.concatenate(sequences), lengths, period, list(demos[0].columns), poses, frames)
    except ModelError as error:
        raise ModelError(f"{source}: {error}") from None
    return model, sequences


def learning_period(demos: list[SignalTable], sample_period: float | None = None) -> float:
    """The period the demonstrations are learned at: `sample_period`, or by default their median
    period but not finer than `COARSEST_DEFAULT_PERIOD`."""
    return max(median_period(demos), COARSEST_DEFAULT_PERIOD) if sample_period is None else sample_period


def _check_settings(n_states: int, sample_period: float | None) -> None:
    if not 1 <= n_states <= MAX_STATES:
        raise ModelError(f"K must be from 1 to {MAX_STATES} (got {n_states})")
    if sample_period is not None and not (math.isfinite(sample_period) and sample_period > 0):
        raise ModelError(f"the sample period must be a positive number of seconds (got {sample_period:g})")


SPREAD_BLOCKS = {"spread_mm": (("x", "y", "z"), 1000.0), "spread_deg": (("rx", "ry", "rz"), 180.0 / np.pi)}


def summary_rows(model: HSMM) -> list[dict]:
    """Per state: mean of each signal, spread (position in mm, orientation in degrees: the
    standard deviation along the state's widest direction, where the model has them), duration
    mean and std (s), most likely successor."""
    transmat = model.normalized_transmat()
    rows = []
    for k in range(model.n_states):
        successor = int(np.argmax(transmat[k])) + 1 if transmat[k].sum() > 0 else None
        rows.append(
            {
                "state": k + 1,
                "mean": {name: float(value) for name, value in zip(model.signal_names_, model.means_[k])},
                "spread": state_spreads(model, k),
                "duration_mean": float(model.duration_means_[k]),
                "duration_std": float(model.duration_stds_[k]),
                "successor": successor,
            }
        )
    return rows


def state_spreads(model: HSMM, state: int) -> dict[str, float]:
    """`spread_mm` and `spread_deg` of a state (those of the blocks the model has): the square
    root of the largest eigenvalue of its covariance over x, y, z (rx, ry, rz), in mm (deg)."""
    names = list(model.signal_names_)
    spreads = {}
    for column, (block, unit) in SPREAD_BLOCKS.items():
        if set(block) <= set(names):
            indices = [names.index(name) for name in block]
            covariance = np.asarray(model.covars_[state])[np.ix_(indices, indices)]
            spreads[column] = float(np.sqrt(max(np.linalg.eigvalsh(covariance)[-1], 0.0)) * unit)
    return spreads


def demonstrated_skill(model: HSMM, folder: str | Path) -> HSMM:
    """`model` itself, or for a TP-HSMM the skill at the first demonstration's frame poses
    (what `stlopt learn` prints and draws)."""
    if not isinstance(model, TPHSMM):
        return model
    poses = load_demo_frames(load_demos(folder))
    return model.at(poses[0] if poses else {})


def frame_poses(model: HSMM, assignments: list[str], source: str | Path, option: str | None = None) -> dict[str, Pose]:
    """Frame name -> pose from `NAME=x,y,z[,yaw]` texts: every frame of a TP-HSMM but `base`,
    none for a plain HSMM. Errors name `option` (default: the `frame` setting as the user
    spells it)."""
    option = option or spelled("frame")
    frames = [name for name in getattr(model, "frame_names_", []) if name != BASE_FRAME]
    poses: dict[str, Pose] = {}
    for text in assignments:
        name, pose = parse_assignment(text, option)
        if name not in frames:
            known = f"its frames: {', '.join(frames)}" if frames else "it was learned without frames"
            raise ModelError(f"{option} {text}: the model {source} has no frame '{name}' ({known})")
        if name in poses:
            raise ModelError(f"{option} {text}: {name} is placed twice")
        poses[name] = pose
    missing = [name for name in frames if name not in poses]
    if missing:
        raise ModelError(f"{source}: the model follows frames {', '.join(frames)}; give the pose of {', '.join(missing)} ({option} NAME=x,y,z[,yaw])")
    return poses
