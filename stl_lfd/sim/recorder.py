"""One recorder for every backend: each step's hand pose, fingers, wrench and object poses in,
the signal columns of `Scene.recorded_signals` out.

A simulating backend fills a `Recorder` at every physics step and calls `rollout` at the end,
which resamples to the recording rate; the kinematic backend hands its arrays, already at the
recording times, to `signal_columns`. Either way the columns are built here and only here:

    t, x, y, z, gripper, force, qx, qy, qz, qw, tilt, fx, fy, fz, tx, ty, tz,
    then NAME_x, NAME_y, NAME_z of each scene frame, then each frame's NAME_tilt.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.choices import WRENCH_SIGNALS
from stl_lfd.errors import ExecutionError
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.reference import Reference, Rollout, recording_times
from stl_lfd.sim.scene import Scene


@dataclass
class Steps:
    """What a backend observed at `S` instants.

    Attributes:
        times: `S` seconds.
        positions: `S x 3` grasp-target positions (m, base frame).
        orientations: `S x 4` hand orientations (unit quaternions x, y, z, w).
        gripper: `S` finger openings (m).
        wrench: `S x 6` external force (N) and torque (Nm) at the wrist, base frame.
        frame_positions: `S x F x 3` positions of the scene's frames.
        frame_orientations: `S x F x 4` orientations of the frames' first objects.
    """

    times: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    gripper: np.ndarray
    wrench: np.ndarray
    frame_positions: np.ndarray
    frame_orientations: np.ndarray


def signal_columns(steps: Steps, scene: Scene, times: np.ndarray) -> dict[str, np.ndarray]:
    """The recorded signals at `times` (within `steps.times`), interpolated linearly between
    steps (`times` that are `steps.times` itself are taken as they are); orientations are
    renormalised after interpolation, so they must be continuous (no sign flips) in `steps`."""

    def at(values: np.ndarray) -> np.ndarray:
        if times is steps.times:
            return values
        if values.ndim == 1:
            return np.interp(times, steps.times, values)
        return np.stack([at(values[:, index]) for index in range(values.shape[1])], axis=1)

    positions = at(steps.positions)
    orientations = at(steps.orientations)
    if times is not steps.times:
        orientations = orientations / np.linalg.norm(orientations, axis=1, keepdims=True)
    wrench = at(steps.wrench)
    columns = {"x": positions[:, 0], "y": positions[:, 1], "z": positions[:, 2], "gripper": at(steps.gripper)}
    columns["force"] = np.linalg.norm(wrench[:, :3], axis=1)
    columns.update(zip(QUATERNION_COLUMNS, orientations.T))
    columns["tilt"] = rotations.tilt(orientations)
    columns.update(zip(WRENCH_SIGNALS, wrench.T))
    for index, frame in enumerate(scene.frames):
        columns.update(zip(frame.signals, at(steps.frame_positions[:, index]).T))
    tilts = rotations.uprightness(steps.frame_orientations) if scene.frames else np.zeros((len(steps.times), 0))
    for index, frame in enumerate(scene.frames):
        columns[frame.tilt_signal] = np.interp(times, steps.times, tilts[:, index])
    return columns


class Recorder:
    """Collects `steps + 1` instants of a simulated rollout (the reset and every step after it)."""

    def __init__(self, step_times: np.ndarray, frames: int) -> None:
        count = len(step_times)
        self.steps = Steps(
            times=np.asarray(step_times, dtype=float),
            positions=np.empty((count, 3)),
            orientations=np.empty((count, 4)),
            gripper=np.empty(count),
            wrench=np.empty((count, 6)),
            frame_positions=np.empty((count, frames, 3)),
            frame_orientations=np.empty((count, frames, 4)),
        )

    def record(self, step: int, pose: tuple[np.ndarray, np.ndarray], gripper: float, wrench: np.ndarray, frames: tuple[np.ndarray, np.ndarray]) -> None:
        """Instant `step`: the hand's `(position, orientation)`, the finger opening, the `6`
        wrist wrench, and the frames' `(F x 3 positions, F x 4 orientations)`."""
        steps = self.steps
        steps.positions[step], steps.orientations[step] = pose
        steps.gripper[step] = gripper
        steps.wrench[step] = wrench
        steps.frame_positions[step], steps.frame_orientations[step] = frames

    def rollout(self, reference: Reference, scene: Scene, rate: float, source: str) -> Rollout:
        """The recorded signals at `rate` samples/s, and the tracking error against `reference`."""
        if not np.isfinite(self.steps.positions).all():
            raise ExecutionError(f"{source}: the simulation diverged (non-finite hand positions)")
        times = recording_times(reference.duration, rate)
        times = times[times <= self.steps.times[-1] + 1e-9]
        self.steps.orientations = rotations.continuous(self.steps.orientations)
        columns = signal_columns(self.steps, scene, times)
        recorded = np.column_stack([columns[axis] for axis in "xyz"])
        error = np.linalg.norm(recorded - reference.positions_at(times), axis=1)
        return Rollout(SignalTable(times, columns, source=source), error)
