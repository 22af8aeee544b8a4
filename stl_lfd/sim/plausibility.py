"""Signals recorded outside stlopt (told with `stlopt tell`, or written by an executor command)
must look like a recording of this robot executing this reference before they become a trial.

A recording that is not (positions far outside the workspace, an absurd force, times in
milliseconds, samples at uneven times) is refused with one line naming the file and the row:
scored, it would become a trial whose robustness is nonsense, and the optimiser's model of the
objective would be ruined for the rest of the run. A recording that is plausible but strays
from the reference by more than the scene's tracking tolerance is kept, with a warning.

The limits: the hand's position within `POSITION_MARGIN` of the scene's safety workspace and
the object frames' within `OBJECT_MARGIN`; the `force` column (when recorded) from 0 to the scene's
`safety.max_force` (default `DEFAULT_MAX_FORCE`); angles (`tilt` 0 to pi, `NAME_tilt` 0 to
pi/2) and the orientation's quaternion of unit norm, within `ANGLE_TOLERANCE` and
`UNIT_TOLERANCE`; the outcome signals in their ranges (`NAME_held` 0 to 1, `NAME_speed` and
`NAME_offset` at least 0); times in seconds from 0 to at least the rollout's duration and at
most `LONGEST` times it, uniformly sampled, at least `1 / RATE_FACTOR` times as often as asked.
"""

from __future__ import annotations

import math

import numpy as np

from stl_lfd.errors import SignalError
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.reference import Reference
from stl_lfd.sim.scene import Scene

POSITION_MARGIN = 0.25  # m beyond the workspace box: a robot's tracking error, not a typo
OBJECT_MARGIN = 1.0  # m: an object may fall off the table; one recorded in mm, or in another frame, is further
DEFAULT_MAX_FORCE = 1000.0  # N: far above any contact a Panda survives
LONGEST = 2.0  # a recording may go on past the reference's end (a robot coming to rest), up to twice its duration
RATE_FACTOR = 10.0  # a recording may be finer than asked (a 1 kHz controller), but not ten times coarser
UNIFORM_TOLERANCE = 0.01  # of the step: a recording's clock jitter
ANGLE_TOLERANCE = 1e-6  # rad: rounding of an angle written to a CSV
UNIT_TOLERANCE = 0.01  # of a quaternion's norm, as demonstrations are held to


class ImplausibleSignals(SignalError):
    """Recorded signals that cannot be a recording of the robot executing the reference."""


def check_recorded(signals: SignalTable, reference: Reference, scene: Scene, rate: float) -> None:
    """Raise `ImplausibleSignals` (one line: the file, the row, what is wrong) unless `signals`
    could have been recorded executing `reference` in `scene` at `rate` samples/s."""
    _check_times(signals, reference.duration, rate)
    _check_positions(signals, scene)
    _check_force(signals, scene)
    _check_ranges(signals, scene)
    _check_quaternions(signals, scene)


def _row(signals: SignalTable, index: int) -> str:
    """`FILE:LINE` of sample `index` (the header is line 1)."""
    return f"{signals.source}:{index + 2}"


def _check_times(signals: SignalTable, duration: float, rate: float) -> None:
    times = signals.times
    if times.size < 2:
        raise ImplausibleSignals(f"{signals.source}: {times.size} sample; a recording needs at least 2")
    steps = np.diff(times)
    if not np.all(steps > 0):
        index = int(np.argmax(steps <= 0)) + 1
        raise ImplausibleSignals(f"{_row(signals, index)}: t = {times[index]:g} s does not come after the sample before it ({times[index - 1]:g} s)")
    period = float(np.median(steps))
    if abs(times[0]) > period or times[-1] < duration - period - 1e-9 or times[-1] > duration * LONGEST:
        unit = " (times must be in seconds)" if times[-1] > 100 * duration else ""
        raise ImplausibleSignals(f"{signals.source}: the signals cover {times[0]:g} to {times[-1]:g} s, but the rollout lasts 0 to {duration:g} s{unit}")
    if period * rate > RATE_FACTOR:
        raise ImplausibleSignals(f"{signals.source}: one sample every {period:g} s, but the rollout is recorded at {rate:g} samples/s (every {1 / rate:g} s)")
    uneven = np.abs(steps - period) > UNIFORM_TOLERANCE * period
    if uneven.any():
        index = int(np.argmax(uneven)) + 1
        raise ImplausibleSignals(
            f"{_row(signals, index)}: {steps[index - 1]:g} s after the sample before it, but the samples are {period:g} s apart elsewhere; record at uniform times"
        )


def _check_positions(signals: SignalTable, scene: Scene) -> None:
    if scene.safety is None:
        return
    columns = [("the hand", ("x", "y", "z"), POSITION_MARGIN)]
    columns += [(frame.name, frame.signals, OBJECT_MARGIN) for frame in scene.frames if set(frame.signals) <= set(signals.columns)]
    for what, names, margin in columns:
        lower, upper = np.array(scene.safety.lower) - margin, np.array(scene.safety.upper) + margin
        positions = np.column_stack([signals.columns[name] for name in names])
        outside = np.any((positions < lower) | (positions > upper), axis=1)
        if outside.any():
            index = int(np.argmax(outside))
            point = ", ".join(f"{name}={value:.4g}" for name, value in zip(names, positions[index]))
            raise ImplausibleSignals(
                f"{_row(signals, index)}: {what} at ({point}) is more than {margin:g} m outside the scene's workspace; not a recording of this robot"
            )


def _check_force(signals: SignalTable, scene: Scene) -> None:
    if "force" not in signals.columns:
        return
    limit = scene.safety.max_force if scene.safety is not None and scene.safety.max_force is not None else DEFAULT_MAX_FORCE
    force = signals.columns["force"]
    if np.any(force < 0):
        index = int(np.argmax(force < 0))
        raise ImplausibleSignals(f"{_row(signals, index)}: a force of {force[index]:.4g} N; `force` is the norm of the contact force, never negative")
    if np.any(force > limit):
        index = int(np.argmax(force > limit))
        raise ImplausibleSignals(
            f"{_row(signals, index)}: a force of {signals.columns['force'][index]:.4g} N, above the {limit:g} N a recording may show (the scene's safety.max_force)"
        )


def signal_ranges(scene: Scene) -> dict[str, tuple[float, float, str]]:
    """Recorded signal -> the least and greatest value it can take, and what it is."""
    ranges = {"tilt": (0.0, math.pi, "the hand's tilt (rad)")}
    for frame in scene.frames:
        ranges[frame.tilt_signal] = (0.0, math.pi / 2, f"{frame.name}'s tilt (rad)")
    for frame in scene.moving_frames:
        speed, held = frame.motion_signals
        ranges[speed] = (0.0, math.inf, f"{frame.name}'s speed (m/s)")
        ranges[held] = (0.0, 1.0, f"whether the fingers hold {frame.name} (1 or 0)")
    for frame in scene.frames:
        if frame.into is not None:
            ranges[frame.hole_signals[1]] = (0.0, math.inf, f"{frame.name}'s offset from the hole's axis (m)")
        if frame.onto is not None:
            ranges[frame.target_signals[3]] = (0.0, math.inf, f"{frame.name}'s offset from its target (m)")
    return ranges


def _check_ranges(signals: SignalTable, scene: Scene) -> None:
    for name, (low, high, what) in signal_ranges(scene).items():
        if name not in signals.columns:
            continue
        values = signals.columns[name]
        outside = (values < low - ANGLE_TOLERANCE) | (values > high + ANGLE_TOLERANCE)
        if outside.any():
            index = int(np.argmax(outside))
            raise ImplausibleSignals(f"{_row(signals, index)}: {name} = {values[index]:.4g}, but {what} lies in [{low:g}, {high:g}]")


def _check_quaternions(signals: SignalTable, scene: Scene) -> None:
    """Every orientation the signals hold (the hand's `qx..qw`, a carried object's
    `NAME_qx..NAME_qw`) is a unit quaternion."""
    groups = [("", "the orientation")] + [(f"{frame.name}_", f"{frame.name}'s orientation") for frame in scene.moving_frames]
    for prefix, what in groups:
        names = [prefix + name for name in QUATERNION_COLUMNS]
        if not set(names) <= set(signals.columns):
            continue
        norms = np.linalg.norm(np.column_stack([signals.columns[name] for name in names]), axis=1)
        off = np.abs(norms - 1.0) > UNIT_TOLERANCE
        if off.any():
            index = int(np.argmax(off))
            raise ImplausibleSignals(f"{_row(signals, index)}: {what} {', '.join(names)} has norm {norms[index]:.4g}; a rotation's quaternion has norm 1")
