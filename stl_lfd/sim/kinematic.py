"""The kinematic backend: the reference itself is the recorded signal.

Instant and exact, for tests and quick studies. Nothing can be touched, so `force` is 0, and
the scene's objects stay where they were placed: their frames' positions are constant, even
while grasped.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.reference import Reference, Rollout, recording_times
from stl_lfd.sim.scene import Scene


class KinematicBackend:
    name = "kinematic"

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Callable | None = None) -> Rollout:
        """Sample `reference` at `rate`; `observer` is not called (there is no world to film)."""
        times = recording_times(reference.duration, rate)
        positions = reference.positions_at(times)
        columns = {
            "x": positions[:, 0],
            "y": positions[:, 1],
            "z": positions[:, 2],
            "gripper": reference.gripper_at(times, scene.gripper_opening),
            "force": np.zeros(times.size),
        }
        orientations = reference.orientations_at(times)
        columns.update(zip(QUATERNION_COLUMNS, orientations.T))
        columns["tilt"] = rotations.tilt(orientations)
        for frame in scene.frames:
            for value, name in zip(frame.pose.position, frame.signals):
                columns[name] = np.full(times.size, float(value))
        for frame in scene.frames:
            columns[frame.tilt_signal] = np.full(times.size, float(rotations.uprightness(scene.frame_object_orientation(frame))))
        return Rollout(SignalTable(times, columns, source="kinematic rollout"), np.zeros(times.size))

    def close(self) -> None:
        pass

    def __enter__(self) -> "KinematicBackend":
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()
