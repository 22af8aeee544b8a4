"""Size guards: the largest inputs stlopt accepts, checked before any work so that a typo
(`--rate 1e7`, a model with durations of days) is a clear error, not an exhausted machine.

The limits are far above any real use: a trajectory of 2 million samples is 5.5 hours at
100 Hz, or 14 minutes at the 2.4 kHz of the simulator.
"""

from __future__ import annotations

import math

MAX_SAMPLES = 2_000_000  # samples of one trajectory (retrieval, rollout, resampled demo)
MAX_RATE = 10_000.0  # samples per second
MAX_TRIALS = 10_000  # trials of one run
MAX_SEED = 2**32 - 1  # what numpy and torch accept
MAX_STATES = 200  # HSMM states
MAX_WORKERS = 256  # parallel trials of one run (one process each)
MAX_PLACEMENTS = 64  # object placements a trial executes at (one rollout each)
MAX_RESTARTS = 1000  # EM starts of one learning (each a full EM run)
MAX_SYMMETRY = 360  # yaws under which an object looks the same (a 1-degree pattern)
MAX_YAW = 4 * math.pi  # rad: a yaw beyond two turns either way is a unit mistake (degrees?)
# The least spread a state may be widened to: beyond these it is no longer the demonstrated skill.
MAX_SPREAD_POSITION = 1.0  # m
MAX_SPREAD_ANGLE = math.pi  # rad
MAX_SPREAD_DURATION = 10.0  # times the duration mean


def samples_problem(duration: float | None, rate: float) -> str:
    """Why a trajectory of `duration` seconds (None: not known yet, only the rate is checked) at
    `rate` samples per second is refused, or ''."""
    if duration is not None and (not math.isfinite(duration) or duration <= 0):
        return f"the duration must be a positive number of seconds (got {duration:g})"
    if not math.isfinite(rate) or rate <= 0:
        return f"the rate must be a positive number of samples per second (got {rate:g})"
    if rate > MAX_RATE:
        return f"the rate {rate:g} samples/s is above the limit of {MAX_RATE:g} samples/s"
    samples = (duration or 0.0) * rate
    if samples > MAX_SAMPLES:
        return f"{duration:g} s at {rate:g} samples/s is {samples:.3g} samples, above the limit of {MAX_SAMPLES:,} per trajectory"
    return ""
