"""One recorder for every backend: each step's hand pose, fingers, wrench and object poses in,
the signal columns of `Scene.recorded_signals` out.

A simulating backend fills a `Recorder` at every physics step and calls `rollout` at the end,
which resamples to the recording rate; the kinematic backend hands its arrays, already at the
recording times, to `signal_columns`. Either way the columns are built here and only here:

    t, x, y, z, gripper, force, qx, qy, qz, qw, tilt, fx, fy, fz, tx, ty, tz,
    then NAME_x, NAME_y, NAME_z of each scene frame, then each frame's NAME_tilt,
    then NAME_speed, NAME_held of each frame that moves with an object,
    then NAME_depth, NAME_offset of each frame that goes into a hole, ..., NAME_inside of each
    frame put inside a container,
    then NAME_clearance of each object declared with one (`stl_lfd.sim.clearance`).
"""

from __future__ import annotations

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.choices import WRENCH_SIGNALS
from stl_lfd.errors import ExecutionError
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.clearance import clearance_columns
from stl_lfd.sim.reference import Reference, Rollout, recording_times
from stl_lfd.sim.scene import Scene, SceneFrame
from stl_lfd.sim.shapes import extents_along, lowest_heights
from stl_lfd.sim.steps import Steps


def signal_columns(steps: Steps, scene: Scene, times: np.ndarray) -> dict[str, np.ndarray]:
    """The recorded signals at `times` (within `steps.times`), in the order of
    `Scene.recorded_signals`, interpolated linearly between steps (`times` that are
    `steps.times` itself are taken as they are); orientations are renormalised after
    interpolation, so they must be continuous (no sign flips) in `steps`."""

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
    moving = {frame.name for frame in scene.moving_frames}
    for index, frame in enumerate(scene.frames):
        columns[frame.tilt_signal] = np.interp(times, steps.times, tilts[:, index])
        if frame.name in moving:
            turns = at(rotations.continuous(steps.frame_orientations[:, index]))
            columns.update(zip(frame.orientation_signals, (turns / np.linalg.norm(turns, axis=1, keepdims=True)).T))
    columns.update({name: at(values) for name, values in outcome_columns(steps, scene).items()})
    if any(item.clearance for item in scene.objects):  # distances cost: taken at the recording times only
        held = at(steps.frame_held.astype(float)) if steps.frame_held.size else steps.frame_held
        frames = np.stack([at(steps.frame_positions[:, index]) for index in range(len(scene.frames))], axis=1) if scene.frames else steps.frame_positions
        turns = [at(rotations.continuous(steps.frame_orientations[:, index])) for index in range(len(scene.frames))]
        turns_array = np.stack([turn / np.linalg.norm(turn, axis=1, keepdims=True) for turn in turns], axis=1) if turns else steps.frame_orientations
        at_times = Steps(times, positions, orientations, columns["gripper"], wrench, frames, turns_array, np.asarray(held) > 0.5)
        columns.update(clearance_columns(at_times, scene))
    return {name: columns[name] for name in scene.recorded_signals}  # in the order the scene lists them


def outcome_columns(steps: Steps, scene: Scene) -> dict[str, np.ndarray]:
    """At `steps.times`: the speed and held flag of each frame that moves with an object, and the
    depth below the rim and offset from the axis of each frame that goes into a hole."""
    index = {frame.name: number for number, frame in enumerate(scene.frames)}
    columns: dict[str, np.ndarray] = {}
    for frame in scene.moving_frames:
        positions = steps.frame_positions[:, index[frame.name]]
        velocities = np.gradient(positions, steps.times, axis=0) if len(steps.times) > 1 else np.zeros_like(positions)
        speed_signal, held_signal = frame.motion_signals
        columns[speed_signal] = np.linalg.norm(velocities, axis=1)
        columns[held_signal] = steps.frame_held[:, index[frame.name]].astype(float)
    for frame in scene.frames:
        if frame.into is None:
            continue
        item = scene.carried_object(frame)
        hole = scene.frames[index[frame.into]]
        orientations = steps.frame_orientations[:, index[frame.name]]
        centres = steps.frame_positions[:, index[frame.name]] - rotations.rotate(orientations, np.tile(scene.origin_in_object(frame), (len(steps.times), 1)))
        hole_positions = steps.frame_positions[:, index[hole.name]]
        depth_signal, offset_signal = frame.hole_signals
        columns[depth_signal] = hole_positions[:, 2] + hole.rim - lowest_heights(item.shape, item.size, centres, orientations)
        columns[offset_signal] = np.hypot(*(centres[:, :2] - hole_positions[:, :2]).T)
    for frame in scene.frames:
        if frame.onto is not None:
            columns.update(target_columns(steps, scene, frame, index))
        if frame.inside is not None:
            columns[frame.inside_signal] = inside_column(steps, scene, frame, index)
    return columns


def inside_column(steps: Steps, scene: Scene, frame: SceneFrame, index: dict[str, int]) -> np.ndarray:
    """At `steps.times`: how far a frame's whole object is inside its container's interior box
    (`SceneFrame.inside_signal`): the least margin between the object's extent and the box's six
    faces, along the container's first object's axes as it stands."""
    item = scene.carried_object(frame)
    orientations = steps.frame_orientations[:, index[frame.name]]
    centres = steps.frame_positions[:, index[frame.name]] - rotations.rotate(orientations, np.tile(scene.origin_in_object(frame), (len(steps.times), 1)))
    container = scene.frames[index[frame.inside]]
    origins, turns = steps.frame_positions[:, index[container.name]], steps.frame_orientations[:, index[container.name]]
    axes = rotations.to_matrix(turns).swapaxes(-1, -2)  # S x 3 x 3: the container's axes (rows), base frame
    local = rotations.rotate(rotations.conjugate(turns), centres - origins)  # the object's centre in the container's frame
    reach = extents_along(item.shape, item.size, orientations, axes)
    lower, upper = (np.asarray(corner, dtype=float) for corner in container.interior)
    return np.minimum(upper - (local + reach), (local - reach) - lower).min(axis=1)


def target_columns(steps: Steps, scene: Scene, frame: SceneFrame, index: dict[str, int]) -> dict[str, np.ndarray]:
    """At `steps.times`: how a frame's object sits on its target (`SceneFrame.target_signals`):
    the height of its lowest point above the target's origin, and its centre's offset from that
    origin along the x and y axes of the target's first object, as it stands."""
    item = scene.carried_object(frame)
    orientations = steps.frame_orientations[:, index[frame.name]]
    centres = steps.frame_positions[:, index[frame.name]] - rotations.rotate(orientations, np.tile(scene.origin_in_object(frame), (len(steps.times), 1)))
    target = index[frame.onto]
    origins, turns = steps.frame_positions[:, target], steps.frame_orientations[:, target]
    dx, dy = rotations.rotate(rotations.conjugate(turns), centres - origins)[:, :2].T
    height = lowest_heights(item.shape, item.size, centres, orientations) - origins[:, 2]
    return dict(zip(frame.target_signals, (height, dx, dy, np.hypot(dx, dy))))


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
            frame_held=np.empty((count, frames)),
        )

    def record(
        self, step: int, pose: tuple[np.ndarray, np.ndarray], gripper: float, wrench: np.ndarray, frames: tuple[np.ndarray, np.ndarray], held: np.ndarray
    ) -> None:
        """Instant `step`: the hand's `(position, orientation)`, the finger opening, the `6`
        wrist wrench, the frames' `(F x 3 positions, F x 4 orientations)` and which frames'
        objects the fingers hold (`F`, 1 or 0)."""
        steps = self.steps
        steps.positions[step], steps.orientations[step] = pose
        steps.gripper[step] = gripper
        steps.wrench[step] = wrench
        steps.frame_positions[step], steps.frame_orientations[step] = frames
        steps.frame_held[step] = held

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
