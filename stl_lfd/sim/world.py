"""A simulated Panda's rollout, whatever the engine: the `World` an engine offers, and the one
loop that drives it along a reference and records it.

Every 240 Hz step (`TIME_STEP`) the loop carries out the reference's gripper events, moves the
impedance controller's equilibrium to the reference's pose at the world's time (with its twist
and acceleration fed forward, `impedance.py`) and the fingers' target to its opening, advances
the world by one step
(engines take finer physics steps inside), and records the hand, the fingers, the wrist wrench
and the scene's frames. The wrench is low-pass filtered as a force sensor's electronics would
(`Scene.force_filter_hz`); the recorder resamples everything to the recording rate.

A grasp is the fingers closing with the scene's finger force on whatever is between them: the
object is held by friction alone. The `grasp` event only declares the object as the hand's load
once the grasp action is over (as a Franka user sets the load after grasping: declared while
the object still stands on the table, its weight would be read as a force and lifted by the
arm), so that the wrist sensor's reading has its weight removed; it fails the rollout when no
movable object is within the scene's grasp distance of the hand.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ExecutionError
from stl_lfd.sim.backend import Observer
from stl_lfd.sim.impedance import reference_twists
from stl_lfd.sim.recorder import Recorder
from stl_lfd.sim.reference import TIME_STEP, Reference, Rollout
from stl_lfd.sim.scene import Camera, Scene, SceneObject


@dataclass(frozen=True)
class Target:
    """Where the controller is sent at one step: the hand's `position` (m) and `orientation`
    (quaternion x, y, z, w), their `twist` (`6`, m/s and rad/s) and its rate `acceleration`
    (`6`), and the finger `opening` (m)."""

    position: np.ndarray
    orientation: np.ndarray
    twist: np.ndarray
    acceleration: np.ndarray
    opening: float


class World(Protocol):
    """A simulated Panda in a scene, as the rollout loop uses it."""

    def reset(self, target: Target) -> None:
        """Restore the initial state with the hand at rest at `target`'s pose and opening."""

    def command(self, target: Target) -> None:
        """Send the controller to `target` (applied during the next `step`)."""

    def step(self) -> None:
        """Advance by `TIME_STEP`."""

    def hand_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and orientation (quaternion x, y, z, w) of the grasp target."""

    def gripper_opening(self) -> float:
        """Distance (m) between the fingers."""

    def wrench(self) -> np.ndarray:
        """`6`: the external force (N) and torque (Nm) on the hand, base frame, measured at the
        wrist with the hand's and its declared load's weight removed."""

    def frame_poses(self) -> tuple[np.ndarray, np.ndarray]:
        """`F x 3` positions of the scene's frames and `F x 4` orientations of their first objects."""

    def object_poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Movable object name -> its position and orientation now."""

    def held_frames(self) -> np.ndarray:
        """`F`: 1 for each scene frame whose object both fingers touch now, else 0."""

    def declare_load(self, item: SceneObject | None) -> None:
        """The object the hand now holds (None: nothing), for the wrench's compensation."""

    def render(self, camera: Camera) -> np.ndarray:
        """`height x width x 3` uint8 image from `camera`."""


def simulate(world: World, reference: Reference, scene: Scene, rate: float, observer: Observer | None, source: str) -> Rollout:
    """Drive `world` along `reference` and return its signals at `rate` samples/s.

    `observer(time, world)` is called after the reset and after every step (videos, pacing).
    """
    steps = int(round(reference.duration / TIME_STEP))
    step_times = np.arange(steps + 1) * TIME_STEP
    positions, orientations = reference.positions_at(step_times), reference.orientations_at(step_times)
    twists, accelerations = reference_twists(step_times, positions, orientations)
    openings = reference.gripper_at(step_times, scene.gripper_opening)

    def target(step: int) -> Target:
        return Target(positions[step], orientations[step], twists[step], accelerations[step], float(openings[step]))

    recorder = Recorder(step_times, len(scene.frames))
    world.reset(target(0))
    recorder.record(0, world.hand_pose(), world.gripper_opening(), world.wrench(), world.frame_poses(), world.held_frames())
    if observer is not None:
        observer(0.0, world)
    events = list(reference.events)
    load: tuple[float, SceneObject] | None = None  # a grasped object and when it becomes the load
    for step in range(1, steps + 1):
        while events and events[0][0] <= step_times[step] + 1e-9:
            time, action = events.pop(0)
            load = (reference.action_end(time), graspable(world, scene, time)) if action == "grasp" else None
            if load is None:
                world.declare_load(None)
        if load is not None and load[0] <= step_times[step] + 1e-9:
            world.declare_load(load[1])
            load = None
        world.command(target(step - 1))  # the world is at the previous step's time: its target, its twist
        world.step()
        recorder.record(step, world.hand_pose(), world.gripper_opening(), world.wrench(), world.frame_poses(), world.held_frames())
        if observer is not None:
            observer(step_times[step], world)
    recorder.steps.wrench = low_pass(recorder.steps.wrench, scene.force_filter_hz, TIME_STEP)
    return recorder.rollout(reference, scene, rate, source)


def graspable(world: World, scene: Scene, time: float) -> SceneObject:
    """The movable object nearest the grasp target within the scene's grasp distance; an
    ExecutionError naming the nearest one when none is."""
    hand = world.hand_pose()[0]
    items = {item.name: item for item in scene.objects}
    distances = {name: items[name].distance(hand, *pose) for name, pose in world.object_poses().items()}
    reachable = {name: distance for name, distance in distances.items() if distance <= scene.grasp_distance}
    if not reachable:
        nearest = min(distances.values(), default=float("inf"))
        raise ExecutionError(
            f"grasp at t = {time:.2f} s: nothing within {1000 * scene.grasp_distance:.0f} mm of the hand "
            f"at x={hand[0]:.3f} y={hand[1]:.3f} z={hand[2]:.3f} (nearest object {1000 * nearest:.0f} mm away)"
        )
    return items[min(reachable, key=reachable.get)]


class FrameTracker:
    """Where the scene's frames are, from the movable objects' poses: a frame that lists a movable
    object moves rigidly with the first it lists (a grasped shaft's frame goes where the shaft
    goes), and takes that object's orientation; the others stay where the scene has them, with
    their first object's orientation."""

    def __init__(self, scene: Scene) -> None:
        self.positions = np.array([frame.pose.position for frame in scene.frames], dtype=float).reshape(-1, 3)
        self.orientations = np.array([scene.frame_object_orientation(frame) for frame in scene.frames], dtype=float).reshape(-1, 4)
        self.moving: list[tuple[int, str, np.ndarray]] = []  # (frame index, object, the frame's origin in the object's frame)
        for index, frame in enumerate(scene.frames):
            item = scene.carried_object(frame)
            if item is not None:
                self.moving.append((index, item.name, scene.origin_in_object(frame)))

    def poses(self, object_poses: dict[str, tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
        """`F x 3` frame positions and `F x 4` orientations, given movable object name -> (position,
        orientation) now."""
        positions, orientations = self.positions.copy(), self.orientations.copy()
        for index, name, local in self.moving:
            position, orientation = object_poses[name]
            positions[index] = position + rotations.rotate(orientation, local)
            orientations[index] = orientation
        return positions, orientations

    def held(self, objects: set[str]) -> np.ndarray:
        """`F`: 1 for the frames that move with one of `objects` (those the fingers hold), else 0."""
        flags = np.zeros(len(self.positions))
        for index, name, _ in self.moving:
            flags[index] = name in objects
        return flags


def load_torques(jacobian: np.ndarray, hand: np.ndarray, centre: np.ndarray, mass: float) -> np.ndarray:
    """`7` joint torques that hold a load of `mass` (kg) centred at `centre` in the hand whose
    grasp target is at `hand` (`jacobian`: its `6 x 7` Jacobian), as a Franka holds the load set
    after a grasp."""
    support = -mass * GRAVITY
    return jacobian.T @ np.concatenate([support, cross(centre - hand, support)])


GRAVITY = np.array([0.0, 0.0, -9.81])


def external_wrench(
    flange_force: np.ndarray,
    flange_torque: np.ndarray,
    flange: np.ndarray,
    tool_point: np.ndarray,
    masses: np.ndarray,
    centres: np.ndarray,
    accelerations: np.ndarray,
) -> np.ndarray:
    """`6`: what the environment exerts on the hand and its load (force, and torque about
    `tool_point`), from the wrist sensor's reading, as Franka's model-based estimate
    (`O_F_ext_hat_K`) gives it: the load's weight and its bodies' `m a` removed (Newton for the
    bodies beyond the sensor: flange force + external force + weight = m a).

    Args:
        flange_force, flange_torque: `3` each, what the flange exerts on the hand (base frame;
            the torque about `flange`).
        flange, tool_point: `3` each, the sensor's origin and the point torques are taken about.
        masses: `B` masses (kg) of the bodies beyond the sensor (hand, fingers, declared load).
        centres, accelerations: `B x 3` their centres of mass and accelerations (m/s^2).
    """
    inertial = masses[:, None] * (accelerations - GRAVITY)  # each body's m (a - g)
    force = inertial.sum(axis=0) - flange_force
    torque = cross(centres - tool_point, inertial).sum(axis=0) - flange_torque - cross(flange - tool_point, flange_force)
    return np.concatenate([force, torque])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of `... x 3` vectors (np.cross costs more than the rest of a step here)."""
    product = np.empty(np.broadcast_shapes(a.shape, b.shape))
    product[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    product[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    product[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return product


def low_pass(values: np.ndarray, cutoff_hz: float, period: float) -> np.ndarray:
    """First-order low-pass filter along the first axis of `values` (`S` or `S x C`), as a
    force sensor's electronics would apply (starts at 0).

    A plain loop (a few ms per rollout): `scipy.signal.lfilter` gives the same values but its
    import takes about a second, which every one-rollout process (`stlopt rollout`, an executor)
    would pay."""
    gain = 1.0 - math.exp(-2.0 * math.pi * cutoff_hz * period)
    values = np.asarray(values, dtype=float)
    filtered = np.empty_like(values)
    state = np.zeros(values.shape[1:])
    for index in range(len(values)):
        state = state + gain * (values[index] - state)  # y[n] = y[n-1] + gain (x[n] - y[n-1])
        filtered[index] = state
    return filtered
