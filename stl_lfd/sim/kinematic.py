"""The kinematic backend: the reference itself is the recorded signal.

Instant and exact, for tests, quick studies and method `plan`'s plans. Nothing can be touched,
so `force` is 0. A grasp (a reference event) takes the movable object nearest the hand, if one
is within the scene's grasp distance, as the PyBullet backend does: from then until the
release, the frames that move with that object follow the hand rigidly (their positions and
tilts are recorded so); nothing falls.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.signals import SignalTable
from stl_lfd.sim.backend import BackendBase, Capabilities, Observer
from stl_lfd.sim.grasp_model import SETTLE_SECONDS, InHand
from stl_lfd.sim.recorder import signal_columns
from stl_lfd.sim.reference import Reference, Rollout, recording_times
from stl_lfd.sim.scene import Scene
from stl_lfd.sim.steps import Steps


class KinematicBackend(BackendBase):
    """Records the reference itself (see the module's docstring)."""

    name = "kinematic"
    capabilities = Capabilities(plays_the_plan=True)
    in_hand: Mapping[str, InHand] | None = None  # where grasped objects settle in the hand (none: where they were grasped)

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Observer | None = None) -> Rollout:
        """Sample `reference` at `rate`; `observer` is not called (there is no world to film)."""
        times = recording_times(reference.duration, rate)
        positions = reference.positions_at(times)
        orientations = reference.orientations_at(times)
        frame_positions, frame_orientations, frame_held = carried_frames(reference, scene, times, positions, orientations, self.in_hand)
        gripper = reference.gripper_at(times, scene.gripper_opening)
        steps = Steps(times, positions, orientations, gripper, np.zeros((times.size, 6)), frame_positions, frame_orientations, frame_held)
        return Rollout(SignalTable(times, signal_columns(steps, scene, times), source="kinematic rollout"), np.zeros(times.size))


def carried_frames(
    reference: Reference,
    scene: Scene,
    times: np.ndarray,
    positions: np.ndarray,
    orientations: np.ndarray,
    in_hand: Mapping[str, InHand] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`T x F x 3` positions of the scene's frames, `T x F x 4` orientations of their first
    objects and `T x F` flags of the frames held (1 from a grasp until the release), at `times`,
    while the hand (`T x 3` positions, `T x 4` orientations) grasps and releases as the
    reference's events say. A grasped frame keeps its pose in the hand at the grasp, or, when
    `in_hand` (frame name -> pose, a `GraspModel`'s) names it, moves there over SETTLE_SECONDS."""
    frame_positions = np.tile(np.array([frame.pose.position for frame in scene.frames], dtype=float).reshape(1, -1, 3), (len(times), 1, 1))
    frame_orientations = np.tile(np.array([scene.frame_object_orientation(frame) for frame in scene.frames]).reshape(1, -1, 4), (len(times), 1, 1))
    frame_held = np.zeros((len(times), len(scene.frames)))
    objects = {item.name: item for item in scene.objects}
    held: list[int] = []  # the frames moving with the grasped object
    start = 0
    for time, action in list(reference.events) + [(np.inf, "release")]:
        step = int(np.searchsorted(times, time - 1e-9))
        if held:  # carried from `start` to `step`: rigidly with the hand, or settling into its learned pose
            hand = orientations[start]
            for index in held:
                local = rotations.rotate(rotations.conjugate(hand), frame_positions[start, index] - positions[start])
                turned = rotations.multiply(rotations.conjugate(hand), frame_orientations[start, index])
                carried = slice(start, step)
                local, turned = _settling(InHand(local, turned), (in_hand or {}).get(scene.frames[index].name), times[carried] - times[start])
                frame_positions[carried, index] = positions[carried] + rotations.rotate(orientations[carried], local)
                frame_orientations[carried, index] = rotations.multiply(orientations[carried], turned)
                frame_positions[step:, index] = frame_positions[step - 1, index]  # let go: it stays where it was put
                frame_orientations[step:, index] = frame_orientations[step - 1, index]
                frame_held[carried, index] = 1.0
            held = []
        if action == "grasp" and step < len(times):
            held = _grasped(scene, objects, positions[step], frame_positions[step], frame_orientations[step])
            start = step
    return frame_positions, frame_orientations, frame_held


def _settling(at_grasp: InHand, learned: InHand | None, elapsed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`C x 3` positions and `C x 4` orientations in the hand at `elapsed` (`C` seconds since the
    grasp): `at_grasp` throughout, or from it to `learned` over SETTLE_SECONDS."""
    if learned is None:
        return np.tile(at_grasp.position, (len(elapsed), 1)), np.tile(at_grasp.orientation, (len(elapsed), 1))
    share = np.clip(elapsed / SETTLE_SECONDS, 0.0, 1.0)[:, None]
    turn = rotations.log_map(at_grasp.orientation, learned.orientation)
    return at_grasp.position + share * (learned.position - at_grasp.position), rotations.exp_map(at_grasp.orientation, share * turn)


def _grasped(scene: Scene, objects: dict, hand: np.ndarray, frame_positions: np.ndarray, frame_orientations: np.ndarray) -> list[int]:
    """The frames that move with the movable object nearest `hand` within the grasp distance
    (none when there is none), the frames at the given poses now."""
    reach = []
    for index, frame in enumerate(scene.frames):
        movable = [objects[name] for name in frame.objects if objects[name].mass > 0]
        if movable:
            offset = frame_positions[index] - np.asarray(frame.pose.position)  # where the frame has moved
            turned = rotations.multiply(frame_orientations[index], rotations.conjugate(scene.frame_object_orientation(frame)))
            item = movable[0]
            position = np.asarray(frame.pose.position) + offset + rotations.rotate(turned, np.asarray(item.position) - np.asarray(frame.pose.position))
            reach.append((item.distance(hand, position, rotations.multiply(turned, rotations.from_euler(*item.orientation))), index))
    reach = [(distance, index) for distance, index in reach if distance <= scene.grasp_distance]
    return [min(reach)[1]] if reach else []
