"""What a backend executes (`Reference`) and what it returns (`Rollout`), and the reference CSV
that carries a reference to an executor outside stlopt.

Reference CSV: a header `t,x,y,z,gripper,skill,state,event,qx,qy,qz,qw` and one row per
sample at the simulation rate (240 Hz): time (s, from 0), grasp-target position (m, robot base
frame), finger opening (m), the skill (or action) the sample belongs to, its HSMM state
(1-based, 0 during an action), `grasp` or `release` on the sample where that action starts
(empty otherwise), and the hand's orientation (a unit quaternion in the base frame, scalar
last; straight down for skills without orientation). The orientation comes last, so that
executors that read the first eight columns keep working. Numbers are written so that they
read back exactly.
"""

from __future__ import annotations

import csv
import io
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ExecutionError, SignalError
from stl_lfd.files import UnreadableFile, read_text, write_atomically
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable

# The rate at which references are given and the simulator steps: PyBullet's default 240 Hz.
SIMULATION_RATE = 240.0
TIME_STEP = 1.0 / SIMULATION_RATE

ACTIONS = ("grasp", "release")


class TrackingWarning(UserWarning):
    """The robot did not follow the reference (typically: a target outside the workspace)."""


@dataclass
class Reference:
    """A reference end-effector trajectory, and optionally gripper commands.

    Attributes:
        times: `T` strictly increasing seconds, starting at 0.
        positions: `T x 3` grasp-target positions (m) in the robot base frame.
        gripper: `T` finger openings (m), or None to keep the scene's opening.
        events: `(time, action)` pairs, action `grasp` (take the movable object nearest the
            hand) or `release` (let it go).
        skills: `T` names of the skill (or action) each sample belongs to, or None.
        states: `T` HSMM states (1-based; 0 during an action) followed at each sample, or None.
        orientations: `T x 4` hand orientations (unit quaternions x, y, z, w, base frame), or
            None for the hand pointing straight down (`rotations.DOWN`).
    """

    times: np.ndarray
    positions: np.ndarray
    gripper: np.ndarray | None = None
    events: tuple[tuple[float, str], ...] = ()
    skills: np.ndarray | None = None
    states: np.ndarray | None = None
    orientations: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.times = np.asarray(self.times, dtype=float)
        self.positions = np.asarray(self.positions, dtype=float)
        if self.times.ndim != 1 or self.times.size < 2:
            raise ExecutionError("reference: needs at least two samples")
        if self.positions.shape != (self.times.size, 3):
            raise ExecutionError(f"reference: positions must be {self.times.size} x 3 (got {' x '.join(map(str, self.positions.shape))})")
        if self.gripper is not None:
            self.gripper = np.asarray(self.gripper, dtype=float)
            if self.gripper.shape != self.times.shape:
                raise ExecutionError("reference: gripper commands must have one value per sample")
        _require_finite("t", self.times[:, None], self.times)
        _require_finite("x, y, z", self.positions, self.times)
        if self.gripper is not None:
            _require_finite("gripper", self.gripper[:, None], self.times)
        if self.orientations is not None:
            self.orientations = np.asarray(self.orientations, dtype=float)
            if self.orientations.shape != (self.times.size, 4):
                raise ExecutionError(f"reference: orientations must be {self.times.size} x 4 quaternions")
            _require_finite("qx, qy, qz, qw", self.orientations, self.times)
            norms = np.linalg.norm(self.orientations, axis=1)
            if np.any(np.abs(norms - 1.0) > rotations.UNIT_TOLERANCE):
                index = int(np.argmax(np.abs(norms - 1.0)))
                raise ExecutionError(f"reference: qx, qy, qz, qw is not a unit quaternion at sample {index + 1} (norm {norms[index]:.4g})")
            self.orientations = rotations.continuous(self.orientations / norms[:, None])
        for name in ("skills", "states"):
            labels = getattr(self, name)
            if labels is not None and np.shape(labels) != self.times.shape:
                raise ExecutionError(f"reference: {name} must have one value per sample")
        if np.any(np.diff(self.times) <= 0):
            raise ExecutionError("reference: times must be strictly increasing")
        for time, action in self.events:
            if action not in ACTIONS:
                raise ExecutionError(f"reference: unknown action '{action}' (known: {', '.join(ACTIONS)})")
            if not self.times[0] <= time <= self.times[-1]:
                raise ExecutionError(f"reference: {action} at t = {time:g} s is outside the reference")
        self.events = tuple(sorted(self.events))

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0])

    def action_end(self, time: float) -> float:
        """When the action that starts at `time` is over: the first later sample that belongs to
        another skill or action (`time` itself for a reference without skill labels)."""
        if self.skills is None:
            return time
        start = int(np.searchsorted(self.times, time - 1e-9))
        later = np.flatnonzero(self.skills[start:] != self.skills[start])
        return float(self.times[start + later[0]]) if later.size else float(self.times[-1])

    def positions_at(self, times: np.ndarray) -> np.ndarray:
        """`len(times) x 3` positions by linear interpolation (held at the ends)."""
        return np.column_stack([np.interp(times, self.times, self.positions[:, axis]) for axis in range(3)])

    def orientations_at(self, times: np.ndarray) -> np.ndarray:
        """`len(times) x 4` orientations, interpolated between samples (held at the ends);
        straight down everywhere for a reference without orientations."""
        if self.orientations is None:
            return np.tile(rotations.DOWN, (len(times), 1))
        interpolated = np.column_stack([np.interp(times, self.times, self.orientations[:, axis]) for axis in range(4)])
        return interpolated / np.linalg.norm(interpolated, axis=1, keepdims=True)

    def gripper_at(self, times: np.ndarray, default: float) -> np.ndarray:
        """Commanded openings at `times`, or `default` everywhere without gripper commands."""
        if self.gripper is None:
            return np.full(np.shape(times), default)
        return np.interp(times, self.times, self.gripper)


def _require_finite(what: str, values: np.ndarray, times: np.ndarray) -> None:
    bad = ~np.isfinite(values).all(axis=1)
    if bad.any():
        index = int(np.argmax(bad))
        raise ExecutionError(f"reference: {what} not finite at sample {index + 1} (t = {times[index]:.4g} s)")


@dataclass
class Rollout:
    """A recorded execution.

    Attributes:
        signals: the signal table (`t, x, y, z, gripper, force`) at the recording rate.
        tracking_error: `T` distance (m) between recorded and reference position.
    """

    signals: SignalTable
    tracking_error: np.ndarray

    @property
    def tracking_rms(self) -> float:
        return float(np.sqrt(np.mean(self.tracking_error**2)))

    @property
    def tracking_max(self) -> float:
        return float(self.tracking_error.max())


def recording_times(duration: float, rate: float) -> np.ndarray:
    """Sample times 0, 1/rate, ... up to `duration` (inclusive within rounding)."""
    if not rate > 0:
        raise ExecutionError(f"recording rate must be positive (got {rate})")
    count = int(np.floor(duration * rate + 1e-9)) + 1
    return np.arange(count) / rate


def warn_if_untracked(rollout: Rollout, reference: Reference, tolerance: float) -> None:
    """Warn with the worst error, its time and its target when tracking exceeded `tolerance`."""
    if rollout.tracking_max <= tolerance:
        return
    index = int(np.argmax(rollout.tracking_error))
    time = rollout.signals.times[index]
    target = reference.positions_at(np.array([time]))[0]
    warnings.warn(
        f"the robot did not follow the reference: worst tracking error {1000 * rollout.tracking_max:.1f} mm "
        f"at t = {time:.2f} s (target x={target[0]:.3f} y={target[1]:.3f} z={target[2]:.3f}: outside the workspace, or blocked by contact?)",
        TrackingWarning,
        stacklevel=3,
    )


REFERENCE_COLUMNS = ("t", "x", "y", "z", "gripper", "skill", "state", "event") + QUATERNION_COLUMNS


def write_reference_csv(reference: Reference, path: Path, open_width: float) -> None:
    """Write `reference` as a reference CSV (atomically); `open_width` fills the gripper column
    of a reference that does not command the gripper."""
    gripper = reference.gripper_at(reference.times, open_width)
    skills = reference.skills if reference.skills is not None else np.full(reference.times.shape, "")
    states = reference.states if reference.states is not None else np.zeros(reference.times.shape, dtype=int)
    orientations = reference.orientations_at(reference.times) if reference.orientations is None else reference.orientations
    events = dict(reference.events)
    starts = {int(np.argmin(np.abs(reference.times - time))): action for time, action in events.items()}
    body = io.StringIO()
    body.write(",".join(REFERENCE_COLUMNS) + "\n")
    for index, time in enumerate(reference.times.tolist()):
        x, y, z = reference.positions[index].tolist()
        quaternion = ",".join(repr(value) for value in orientations[index].tolist())
        body.write(f"{time!r},{x!r},{y!r},{z!r},{float(gripper[index])!r},{skills[index]},{int(states[index])},{starts.get(index, '')},{quaternion}\n")
    write_atomically(Path(path), body.getvalue())


def read_reference_csv(path: str | Path) -> Reference:
    """Read a reference CSV (what `stlopt ask` and the command backend hand to an executor).

    Raises:
        SignalError: naming the file and the line of a bad row.
    """
    shown = str(path)
    try:
        text = read_text(path, "reference CSV")
    except UnreadableFile as error:
        raise SignalError(f"{shown}: {error}") from None
    rows = [row for row in csv.reader(io.StringIO(text)) if row]
    if not rows or [name.strip() for name in rows[0]][:4] != ["t", "x", "y", "z"]:
        raise SignalError(f"{shown}:1: not a reference CSV (expected the header {','.join(REFERENCE_COLUMNS)})")
    header = [name.strip() for name in rows[0]]
    index = {name: header.index(name) for name in REFERENCE_COLUMNS if name in header}
    numbers, skills, states, events, quaternions = [], [], [], [], []
    oriented = all(name in index for name in QUATERNION_COLUMNS)
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise SignalError(f"{shown}:{line}: expected {len(header)} values, found {len(row)}")
        try:
            numbers.append([float(row[index[name]]) for name in ("t", "x", "y", "z", "gripper") if name in index])
            states.append(int(row[index["state"]]) if "state" in index else 0)
            if oriented:
                quaternions.append([float(row[index[name]]) for name in QUATERNION_COLUMNS])
        except ValueError:
            raise SignalError(f"{shown}:{line}: not a number where one is expected") from None
        skills.append(row[index["skill"]] if "skill" in index else "")
        if "event" in index and row[index["event"]].strip():
            events.append((numbers[-1][0], row[index["event"]].strip()))
    if len(numbers) < 2:
        raise SignalError(f"{shown}: a reference needs at least two samples")
    data = np.array(numbers)
    try:
        orientations = np.array(quaternions) if oriented else None
        if orientations is not None and np.allclose(orientations, rotations.DOWN, rtol=0, atol=1e-12):
            orientations = None  # straight down throughout: a skill without orientation
        gripper = data[:, 4] if "gripper" in index else None
        return Reference(data[:, 0], data[:, 1:4], gripper, tuple(events), np.array(skills), np.array(states), orientations)
    except ExecutionError as error:
        raise SignalError(f"{shown}: {str(error).removeprefix('reference: ')}") from None
