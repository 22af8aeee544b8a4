"""Choosing the number of states K of a skill: each K of a range learned without one
demonstration and scored on it (leave-one-out), and the smallest K whose held-out score is
within one standard error of the best kept (the "one standard error" rule: more states that
explain new demonstrations no better than noise would only give the optimiser more
parameters).

The held-out log-likelihood per sample is the criterion because a criterion on the training
samples alone (BIC, AIC) keeps rewarding more states: a demonstration's samples are strongly
autocorrelated, so they count as far more evidence than they hold. A demonstration the model
has not seen is only explained better by states that recur across demonstrations.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm.demos import load_demo_frames, load_demos, resample
from stl_lfd.hsmm.learn import learn, learning_period, model_frames
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.orientation import to_model_columns
from stl_lfd.hsmm.spread import MinimumSpread
from stl_lfd.hsmm.tp import TPHSMM
from stl_lfd.limits import MAX_STATES
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable

AUTO_STATES = range(2, 11)  # the Ks `-K auto` tries


@dataclass(frozen=True)
class HeldOutScore:
    """A K's log-likelihood per sample of each demonstration held out: its mean over the
    demonstrations and the mean's standard error."""

    mean: float
    standard_error: float


@dataclass(frozen=True)
class StatesChoice:
    """The chosen K and each tried K's held-out score (None: the K could not be learned from
    the demonstrations left, e.g. too few samples)."""

    chosen: int
    scores: dict[int, HeldOutScore | None]


def parse_states(text: str) -> int | range:
    """`-K`'s value: a number of states, `auto` (`AUTO_STATES`) or a range `LOW-HIGH`."""
    text = text.strip().lower()
    if text == "auto":
        return AUTO_STATES
    match = re.fullmatch(r"(\d+)(?:\s*-\s*(\d+))?", text)
    if match is None:
        raise ModelError(f"K must be a number of states, auto, or a range such as 3-8 (got {text!r})")
    low = int(match.group(1))
    high = int(match.group(2)) if match.group(2) is not None else low
    if not 1 <= low <= high <= MAX_STATES:
        raise ModelError(f"K must be from 1 to {MAX_STATES}, a range from low to high (got {text})")
    return low if match.group(2) is None else range(low, high + 1)


def choose_states(
    folder: str | Path,
    candidates: range,
    sample_period: float | None = None,
    frames: list[str] | None = None,
    restarts: int = 1,
    min_spread: MinimumSpread | None | str = "auto",
    progress: Callable[[int, HeldOutScore | None], None] | None = None,
) -> StatesChoice:
    """The smallest K of `candidates` whose models, each learned without one demonstration of
    `folder` (with these settings, as `learn`), give the held-out demonstrations a log-likelihood
    per sample within one standard error of the best K's; `progress(K, score)` after each K.

    Raises:
        ModelError: fewer than two demonstrations, or no K of the range learned.
    """
    demos = load_demos(folder)
    if len(demos) < 2:
        raise ModelError(f"{folder}: choosing K holds one demonstration out, so it needs at least two (there is {len(demos)}); give K")
    poses = load_demo_frames(demos)
    frames = model_frames(poses, frames, str(folder))
    period = learning_period(demos, sample_period)
    scores: dict[int, HeldOutScore | None] = {}
    for K in candidates:
        scores[K] = _held_out_score(demos, poses, K, period, frames, restarts, min_spread)
        if progress is not None:
            progress(K, scores[K])
    learned = {K: score for K, score in scores.items() if score is not None}
    if not learned:
        raise ModelError(f"{folder}: no K from {candidates.start} to {candidates.stop - 1} could be learned without one demonstration; try smaller K")
    best = max(learned.values(), key=lambda score: score.mean)
    return StatesChoice(min(K for K, score in learned.items() if score.mean >= best.mean - best.standard_error), scores)


def _held_out_score(
    demos: list[SignalTable],
    poses: list[dict[str, Pose]] | None,
    n_states: int,
    period: float,
    frames: list[str] | None,
    restarts: int,
    min_spread: MinimumSpread | None | str,
) -> HeldOutScore | None:
    """The log-likelihood per sample of each demonstration under the model learned from the
    others with `n_states` states (None when one cannot be learned or gives no finite score)."""
    scores = []
    for held in range(len(demos)):
        kept = [index for index in range(len(demos)) if index != held]
        try:
            model, _ = learn(
                [demos[index] for index in kept],
                n_states,
                period,
                poses=[poses[index] for index in kept] if poses else None,
                frames=frames,
                restarts=restarts,
                min_spread=min_spread,
            )
        except (ModelError, ValueError, np.linalg.LinAlgError):
            return None
        scores.append(_log_likelihood_per_sample(model, demos[held], poses[held] if poses else {}, period))
    if not np.all(np.isfinite(scores)):
        return None
    return HeldOutScore(float(np.mean(scores)), float(np.std(scores, ddof=1) / np.sqrt(len(scores))))


def _log_likelihood_per_sample(model: HSMM, demo: SignalTable, poses: dict[str, Pose], period: float) -> float:
    """Log-likelihood per sample of `demo` (resampled to `period`) under `model` (a TP-HSMM at
    the demonstration's frame poses)."""
    skill = model.at(poses) if isinstance(model, TPHSMM) else model
    samples, _, _ = to_model_columns(resample(demo, period), list(demo.columns), skill.orientation)
    with np.errstate(all="ignore"):  # a model that cannot explain the demonstration scores -inf or NaN
        return skill.score(samples) / len(samples)
