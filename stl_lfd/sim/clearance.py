"""Clearances: how far the hand, its fingers and what they hold stay from a scene object (the
signal `NAME_clearance` of an object declared with `clearance: true` or `[hand, ...]`), and how
far two objects are from each other (`NAME_clearance_OTHER`, `clearance: [OTHER]`: 0 or less
while they touch).

The hand is three boxes, in the frame of the grasp target (the recorded `x, y, z` and
orientation; z points from the palm to the fingertips, the fingers close along y): the bounding
boxes of the Franka Hand's collision meshes (the palm, and each finger at its opening), so that a
clearance is never more than the true one. The fingertips reach 7.2 mm past the grasp target.
An object the fingers hold (a frame's object whose `NAME_held` is 1) counts as part of the hand.
Distances are exact for boxes, cylinders and spheres at any pose (the Flexible Collision
Library, `python-fcl`), and signed: negative when the shapes overlap (how deep).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.sim.scene import HAND
from stl_lfd.sim.steps import Steps

if TYPE_CHECKING:
    from stl_lfd.sim.scene import Scene, SceneFrame, SceneObject

# (centre, half extents) in the grasp target's frame (m). Each finger's y centre is its inner
# face's (half the opening) plus FINGER_HALF[1].
PALM = (np.array([0.0, -0.0018, -0.08495]), np.array([0.0316, 0.1022, 0.04595]))
FINGER_HALF = np.array([0.0105, 0.0132, 0.0269])
FINGER_CENTRE_Z = -0.0197


@dataclass(frozen=True)
class Box:
    """A box `centre` (`3`) and `half` extents (`3`) in some frame."""

    centre: np.ndarray
    half: np.ndarray


def hand_boxes(opening: float) -> list[Box]:
    """The palm and the two fingers, at the finger `opening` (m), in the grasp target's frame."""
    side = opening / 2 + FINGER_HALF[1]
    return [Box(*PALM)] + [Box(np.array([0.0, sign * side, FINGER_CENTRE_Z]), FINGER_HALF) for sign in (1.0, -1.0)]


def clearance_columns(steps: Steps, scene: Scene) -> dict[str, np.ndarray]:
    """At `steps.times`: each `clearance` object's signed distance (m) to the hand,
    its fingers and what they hold (`NAME_clearance`)."""
    import fcl  # only scenes that declare clearances pay for it

    request = fcl.DistanceRequest(enable_signed_distance=True)
    objects = {item.name: item for item in scene.objects}
    columns = {}
    for item in scene.objects:
        for other, signal in zip(item.clearance, item.clearance_signals):
            target = _collision_object(fcl, item)
            values = np.empty(len(steps.times))
            for step in range(len(steps.times)):
                _place(fcl, target, *_object_pose(steps, scene, item, step))
                parts = (
                    _hand_parts(fcl, steps, scene, step, item.name)
                    if other == HAND
                    else [_placed_object(fcl, objects[other], *_object_pose(steps, scene, objects[other], step))]
                )
                values[step] = min(fcl.distance(part, target, request, fcl.DistanceResult()) for part in parts)
            columns[signal] = values
    return columns


def _hand_parts(fcl, steps: Steps, scene: Scene, step: int, measured: str) -> list:
    """The hand's boxes at `step`, and each object the fingers hold but `measured`."""
    held = [
        _placed_object(fcl, item, *_frame_object_pose(steps, scene, frame, index, step))
        for index, frame in enumerate(scene.frames)
        if (item := scene.carried_object(frame)) is not None and steps.frame_held[step, index] and item.name != measured
    ]
    return _hand_objects(fcl, steps, step) + held


def _hand_objects(fcl, steps: Steps, step: int) -> list:
    rotation = rotations.to_matrix(steps.orientations[step])
    objects = []
    for box in hand_boxes(float(steps.gripper[step])):
        transform = fcl.Transform(rotation, steps.positions[step] + rotation @ box.centre)
        objects.append(fcl.CollisionObject(fcl.Box(*(2 * box.half)), transform))
    return objects


def _collision_object(fcl, item: SceneObject):
    """An fcl object of `item`'s shape (fcl's boxes take full extents, its cylinders lie along z
    as ours do)."""
    if item.shape == "box":
        shape = fcl.Box(*(2 * np.asarray(item.size)))
    elif item.shape == "cylinder":
        shape = fcl.Cylinder(item.size[0], item.size[1])
    else:
        shape = fcl.Sphere(item.size[0])
    return fcl.CollisionObject(shape, fcl.Transform())


def _placed_object(fcl, item: SceneObject, position: np.ndarray, orientation: np.ndarray):
    placed = _collision_object(fcl, item)
    _place(fcl, placed, position, orientation)
    return placed


def _place(fcl, placed, position: np.ndarray, orientation: np.ndarray) -> None:
    placed.setTransform(fcl.Transform(rotations.to_matrix(orientation), np.asarray(position, dtype=float)))


def _object_pose(steps: Steps, scene: Scene, item: SceneObject, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Where `item` is at `step`: with the frame it is the carried object of, else where the
    scene puts it (it is fixed: `Scene` checks)."""
    for index, frame in enumerate(scene.frames):
        carried = scene.carried_object(frame)
        if carried is not None and carried.name == item.name:
            return _frame_object_pose(steps, scene, frame, index, step)
    return np.asarray(item.position, dtype=float), rotations.from_euler(*item.orientation)


def _frame_object_pose(steps: Steps, scene: Scene, frame: SceneFrame, index: int, step: int) -> tuple[np.ndarray, np.ndarray]:
    """The centre and orientation of the object a frame moves with, at `step`."""
    orientation = steps.frame_orientations[step, index]
    centre = steps.frame_positions[step, index] - rotations.rotate(orientation, scene.origin_in_object(frame))
    return centre, orientation
