"""Learning a skill model from a folder of demonstrations, and its summary."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm.demos import load_demos, median_period, resample
from stl_lfd.hsmm.model import HSMM
from stl_lfd.limits import MAX_STATES, samples_problem
from stl_lfd.signals import SignalTable

# Demonstrations are resampled no finer than this (s): hand-guided motions have no content
# above a few hertz, and EM, state sequences and tracking all cost time per sample.
COARSEST_DEFAULT_PERIOD = 0.02


def learn_from_folder(folder: str | Path, n_states: int = 6, sample_period: float | None = None) -> tuple[HSMM, list[np.ndarray]]:
    """Load every demonstration CSV of `folder`, then `learn`."""
    _check_settings(n_states, sample_period)
    return learn(load_demos(folder), n_states, sample_period, source=str(folder))


def learn(demos: list[SignalTable], n_states: int = 6, sample_period: float | None = None, source: str = "demonstrations") -> tuple[HSMM, list[np.ndarray]]:
    """Resample the demonstrations (signal tables with the same columns) to one period and fit.

    The default period is the demonstrations' median period, but not finer than
    `COARSEST_DEFAULT_PERIOD` (50 Hz).

    Returns:
        the fitted model and the resampled demonstrations (`T_i x D` each).
    """
    _check_settings(n_states, sample_period)
    if not demos:
        raise ModelError(f"{source}: no demonstrations to learn from")
    period = max(median_period(demos), COARSEST_DEFAULT_PERIOD) if sample_period is None else sample_period
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
    model = HSMM(n_states=n_states)
    model.fit(np.concatenate(sequences), np.array([len(s) for s in sequences]), period, list(demos[0].columns))
    return model, sequences


def _check_settings(n_states: int, sample_period: float | None) -> None:
    if not 1 <= n_states <= MAX_STATES:
        raise ModelError(f"K must be from 1 to {MAX_STATES} (got {n_states})")
    if sample_period is not None and not (math.isfinite(sample_period) and sample_period > 0):
        raise ModelError(f"the sample period must be a positive number of seconds (got {sample_period:g})")


def summary_rows(model: HSMM) -> list[dict]:
    """Per state: mean position, duration mean and std (s), most likely successor."""
    transmat = model.normalized_transmat()
    rows = []
    for k in range(model.n_states):
        successor = int(np.argmax(transmat[k])) + 1 if transmat[k].sum() > 0 else None
        rows.append(
            {
                "state": k + 1,
                "mean": {name: float(value) for name, value in zip(model.signal_names_, model.means_[k])},
                "duration_mean": float(model.duration_means_[k]),
                "duration_std": float(model.duration_stds_[k]),
                "successor": successor,
            }
        )
    return rows
