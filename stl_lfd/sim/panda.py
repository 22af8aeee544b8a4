"""The PyBullet backend: a Franka Panda tracking the reference with inverse kinematics.

Every simulation step (240 Hz) computes the inverse kinematics of the grasp-target link (link
11 of `franka_panda/panda.urdf`) for the next reference pose (the reference's orientation, or
the gripper pointing down), and sends the joint targets to the arm's position controllers.
The recording (position, orientation, tilt, gripper, force, object frames) is taken at every
step and resampled to the requested rate at the end.

A world is built once per scene and process (about 0.2 s) and restored to its saved initial
state before each rollout, so the same reference always gives bit-identical signals; scenes
with objects get a fresh world for every rollout instead (see `PyBulletBackend.run`).
"""

from __future__ import annotations

import atexit
import functools
import math
import os
import sys
import time as clock
import weakref
from contextlib import contextmanager
from typing import Callable, Iterator

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ExecutionError
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.reference import TIME_STEP, Reference, Rollout, recording_times
from stl_lfd.sim.scene import Camera, Region, Scene, SceneFrame, SceneObject

END_EFFECTOR_LINK = 11
ARM_JOINTS = list(range(7))
FINGER_JOINTS = [9, 10]
# Elbow up, hand above the table: the posture the inverse kinematics starts from.
REST_POSE = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785, 0.04, 0.04]
GRIPPER_DOWN = tuple(rotations.DOWN)  # the IK target of skills without orientation
GRASP_FORCE = 2000.0  # N: the grasp constraint is stiff enough not to slip under contact  # quaternion (x, y, z, w): rotation by pi about x

Observer = Callable[[float, "PandaWorld"], None]

# Worlds still connected at exit are disconnected while pybullet is intact; left to the
# garbage collector, their clients would fail noisily during interpreter shutdown.
_open_worlds: "weakref.WeakSet[PandaWorld]" = weakref.WeakSet()
atexit.register(lambda: [world.close() for world in list(_open_worlds)])


@contextmanager
def _silenced() -> Iterator[None]:
    """Drop what the pybullet C library prints when it loads and connects (build time,
    argv[0]): stdout carries data such as the signal CSV, stderr is for our messages."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for descriptor in (*saved, null):
            os.close(descriptor)


# The functions called at every simulation step. BulletClient looks each attribute up anew and
# wraps it in a partial on every call (about a tenth of a rollout's time); bound once per
# client instead, they are the same calls.
STEP_FUNCTIONS = (
    "stepSimulation", "calculateInverseKinematics", "setJointMotorControlArray", "getLinkState", "getJointStates",
    "getContactPoints", "getBasePositionAndOrientation", "multiplyTransforms",
)  # fmt: skip


def _bind_step_functions(client, pybullet) -> None:
    for name in STEP_FUNCTIONS:
        setattr(client, name, functools.partial(getattr(pybullet, name), physicsClientId=client._client))


class PandaWorld:
    """One pybullet client holding the floor, the Panda and the scene's objects and regions."""

    def __init__(self, scene: Scene, gui: bool = False) -> None:
        with _silenced():
            import pybullet
            import pybullet_data
            from pybullet_utils import bullet_client

            if gui and not os.environ.get("DISPLAY"):
                raise ExecutionError("the PyBullet GUI needs a display and DISPLAY is not set (record a video instead)")
            mode = pybullet.GUI if gui else pybullet.DIRECT
            self.client = bullet_client.BulletClient(connection_mode=mode)
        _bind_step_functions(self.client, pybullet)
        self.pb = pybullet
        self.scene = scene
        client = self.client
        client.setAdditionalSearchPath(pybullet_data.getDataPath())
        client.setGravity(0, 0, -9.81)
        client.setTimeStep(TIME_STEP)
        if gui:
            client.configureDebugVisualizer(pybullet.COV_ENABLE_GUI, 0)
            camera = scene.camera
            client.resetDebugVisualizerCamera(camera.distance, camera.yaw, camera.pitch, camera.target)
        self.floor = client.loadURDF("plane.urdf")
        self.robot = client.loadURDF("franka_panda/panda.urdf", useFixedBase=True)
        self.objects = {item.name: self._add_object(item) for item in scene.objects}
        self.movable = [self.objects[item.name] for item in scene.objects if item.mass > 0]
        self._items = {self.objects[item.name]: item for item in scene.objects}
        self.held: tuple[int, int] | None = None  # (object body, constraint)
        # Frame origins: fixed ones once; moving ones as (row, body, origin in the body's frame).
        self._frame_positions = np.array([frame.pose.position for frame in scene.frames], dtype=float).reshape(-1, 3)
        self._object_orientations = np.array([scene.frame_object_orientation(frame) for frame in scene.frames], dtype=float).reshape(-1, 4)
        self._moving_frames = [(index, *anchor) for index, frame in enumerate(scene.frames) if (anchor := self._anchor(frame)) is not None]
        for region in scene.regions:
            self._add_region(region)
        for joint, angle in zip(ARM_JOINTS + FINGER_JOINTS, REST_POSE):
            client.resetJointState(self.robot, joint, angle)
        self.initial_state = client.saveState()
        _open_worlds.add(self)

    def _add_object(self, item: SceneObject) -> int:
        pb, client = self.pb, self.client
        if item.shape == "box":
            shape = dict(shapeType=pb.GEOM_BOX, halfExtents=item.size)
            visual = dict(shapeType=pb.GEOM_BOX, halfExtents=item.size)
        elif item.shape == "cylinder":
            shape = dict(shapeType=pb.GEOM_CYLINDER, radius=item.size[0], height=item.size[1])
            visual = dict(shapeType=pb.GEOM_CYLINDER, radius=item.size[0], length=item.size[1])
        else:
            shape = dict(shapeType=pb.GEOM_SPHERE, radius=item.size[0])
            visual = dict(shapeType=pb.GEOM_SPHERE, radius=item.size[0])
        body = client.createMultiBody(
            baseMass=item.mass,
            baseCollisionShapeIndex=client.createCollisionShape(**shape),
            baseVisualShapeIndex=client.createVisualShape(rgbaColor=item.color, **visual),
            basePosition=item.position,
            baseOrientation=client.getQuaternionFromEuler(item.orientation),
        )
        client.changeDynamics(body, -1, lateralFriction=item.friction)
        return body

    def _anchor(self, frame: SceneFrame) -> tuple[int, tuple[float, float, float] | None] | None:
        """None for a fixed frame; for one that moves with its first movable object, that body
        and the frame's origin in the body's frame (None when it is the body's origin)."""
        masses = {item.name: item.mass for item in self.scene.objects}
        movable = [name for name in frame.objects if masses[name] > 0]
        if not movable:
            return None
        body = self.objects[movable[0]]
        position, orientation = self.client.getBasePositionAndOrientation(body)
        inverse = self.client.invertTransform(position, orientation)
        local, _ = self.client.multiplyTransforms(inverse[0], inverse[1], frame.pose.position, (0.0, 0.0, 0.0, 1.0))
        return body, (None if max(abs(value) for value in local) < 1e-12 else local)

    def frame_poses(self) -> tuple[np.ndarray, np.ndarray]:
        """`F x 3` positions of the scene's frames now, and `F x 4` orientations of their first
        objects (a grasped shaft's frame and orientation move with it)."""
        positions, orientations = self._frame_positions.copy(), self._object_orientations.copy()
        for index, body, local in self._moving_frames:
            position, orientation = self.client.getBasePositionAndOrientation(body)
            positions[index] = position if local is None else self.client.multiplyTransforms(position, orientation, local, (0.0, 0.0, 0.0, 1.0))[0]
            orientations[index] = orientation
        return positions, orientations

    def _add_region(self, region: Region) -> int:
        lower, upper = np.array(region.lower), np.array(region.upper)
        visual = self.client.createVisualShape(self.pb.GEOM_BOX, halfExtents=list((upper - lower) / 2), rgbaColor=region.color)
        return self.client.createMultiBody(baseMass=0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=visual, basePosition=list((upper + lower) / 2))

    def reset(self, position: np.ndarray, opening: float, orientation=GRIPPER_DOWN) -> None:
        """Restore the initial state, then place the hand at `position` (and `orientation`, a
        quaternion x, y, z, w) at rest."""
        client = self.client
        self.release()
        client.restoreState(self.initial_state)
        for _ in range(20):
            angles = self._inverse_kinematics(position, iterations=100, orientation=orientation)
            for joint, angle in zip(ARM_JOINTS, angles):
                client.resetJointState(self.robot, joint, angle)
            if np.linalg.norm(self.end_effector() - position) < 1e-6:
                break
        for joint in FINGER_JOINTS:
            client.resetJointState(self.robot, joint, opening / 2)
        # restoreState leaves the previous rollout's contact points (and their forces) in place
        # until the next step: a rollout after one that pushed into the floor started with a
        # force spike. Collision detection at the reset pose replaces them.
        client.performCollisionDetection()

    def command(self, position: np.ndarray, opening: float, orientation=GRIPPER_DOWN) -> None:
        """Send joint targets that bring the hand to `position` (and `orientation`) and the
        fingers to `opening`."""
        control = self.scene.control
        self.client.setJointMotorControlArray(
            self.robot,
            ARM_JOINTS,
            self.pb.POSITION_CONTROL,
            targetPositions=self._inverse_kinematics(position, orientation=orientation),
            forces=control.arm_forces,
            positionGains=[control.position_gain] * len(ARM_JOINTS),
        )
        self.client.setJointMotorControlArray(
            self.robot, FINGER_JOINTS, self.pb.POSITION_CONTROL, targetPositions=[opening / 2] * 2, forces=[control.finger_force] * 2
        )

    def step(self) -> None:
        self.client.stepSimulation()

    def grasp(self, time: float) -> None:
        """Attach the movable object nearest the grasp-target link with a fixed constraint at
        their current relative pose; an ExecutionError when none is within reach."""
        hand = self.end_effector()
        distances = {body: self._distance_to(body, hand) for body in self.movable}
        reachable = {body: distance for body, distance in distances.items() if distance <= self.scene.grasp_distance}
        if not reachable:
            nearest = min(distances.values(), default=float("inf"))
            raise ExecutionError(
                f"grasp at t = {time:.2f} s: nothing within {1000 * self.scene.grasp_distance:.0f} mm of the hand "
                f"at x={hand[0]:.3f} y={hand[1]:.3f} z={hand[2]:.3f} (nearest object {1000 * nearest:.0f} mm away)"
            )
        body = min(reachable, key=reachable.get)
        link_state = self.client.getLinkState(self.robot, END_EFFECTOR_LINK, computeForwardKinematics=1)
        link_position, link_orientation = link_state[4], link_state[5]
        body_position, body_orientation = self.client.getBasePositionAndOrientation(body)
        inverse_position, inverse_orientation = self.client.invertTransform(link_position, link_orientation)
        relative_position, relative_orientation = self.client.multiplyTransforms(inverse_position, inverse_orientation, body_position, body_orientation)
        constraint = self.client.createConstraint(
            self.robot, END_EFFECTOR_LINK, body, -1, self.pb.JOINT_FIXED, [0, 0, 0], relative_position, [0, 0, 0], relative_orientation
        )
        self.client.changeConstraint(constraint, maxForce=GRASP_FORCE)
        self.held = (body, constraint)

    def _distance_to(self, body: int, point: np.ndarray) -> float:
        """Distance (m) from `point` to the surface of `body` (0 when inside)."""
        position, orientation = self.client.getBasePositionAndOrientation(body)
        return self._items[body].distance(point, position, orientation)

    def release(self) -> None:
        """Let go of the held object, if any."""
        if self.held is not None:
            self.client.removeConstraint(self.held[1])
            self.held = None

    def _inverse_kinematics(self, position: np.ndarray, iterations: int = 20, orientation=GRIPPER_DOWN) -> list[float]:
        angles = self.client.calculateInverseKinematics(
            self.robot, END_EFFECTOR_LINK, list(position), list(orientation), maxNumIterations=iterations, residualThreshold=1e-5
        )
        return list(angles[: len(ARM_JOINTS)])

    def end_effector(self) -> np.ndarray:
        """Position (m) of the grasp-target link frame."""
        return self.end_effector_pose()[0]

    def end_effector_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and orientation (quaternion x, y, z, w) of the grasp-target link frame."""
        state = self.client.getLinkState(self.robot, END_EFFECTOR_LINK, computeForwardKinematics=1)
        return np.array(state[4]), np.array(state[5])

    def gripper_opening(self) -> float:
        first, second = self.client.getJointStates(self.robot, FINGER_JOINTS)
        return first[0] + second[0]

    def contact_force(self) -> float:
        """Norm of the summed contact normal forces between the robot (with the object it holds)
        and the rest of the world."""
        tool = {self.robot} | ({self.held[0]} if self.held else set())
        total = np.zeros(3)
        for body in tool:
            for contact in self.client.getContactPoints(bodyA=body):
                if contact[2] not in tool:
                    total += contact[9] * np.asarray(contact[7])
        return float(np.linalg.norm(total))

    def render(self, camera: Camera) -> np.ndarray:
        """`height x width x 3` uint8 image from the scene camera (TinyRenderer, no display)."""
        client, pb = self.client, self.pb
        view = client.computeViewMatrixFromYawPitchRoll(camera.target, camera.distance, camera.yaw, camera.pitch, 0.0, 2)
        projection = client.computeProjectionMatrixFOV(55.0, camera.width / camera.height, 0.05, 5.0)
        _, _, pixels, _, _ = client.getCameraImage(camera.width, camera.height, view, projection, renderer=pb.ER_TINY_RENDERER)
        return np.asarray(pixels, dtype=np.uint8).reshape(camera.height, camera.width, 4)[:, :, :3]

    def close(self) -> None:
        _open_worlds.discard(self)
        try:
            self.client.disconnect()
        except Exception:  # already gone (the GUI window was closed)
            pass


class PyBulletBackend:
    """Runs references on a simulated Panda; keeps one world per scene until `close` (or the
    end of a `with` block)."""

    name = "pybullet"

    def __init__(self, gui: bool = False) -> None:
        self.gui = gui
        self._worlds: dict[Scene, PandaWorld] = {}

    def world(self, scene: Scene, fresh: bool = False) -> PandaWorld:
        """The world of `scene`; `fresh` builds it anew (closing every world kept so far, so
        that rollouts over many object placements keep one world open, not one per placement)."""
        if fresh:
            self.close()
        if scene not in self._worlds:
            self._worlds[scene] = PandaWorld(scene, self.gui)
        return self._worlds[scene]

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Observer | None = None) -> Rollout:
        """Execute `reference` and record `t, x, y, z, gripper, force, qx, qy, qz, qw, tilt` (and
        the object frames' positions) at `rate` samples/s.

        `observer(time, world)` is called after the reset and after every simulation step
        (for videos and for pacing the GUI).
        """
        # Restoring the saved state is bit-exact without contacts; with objects to touch and
        # grasp constraints, consecutive rollouts of the same behaviour alternated between two
        # results (measured: -0.060716 / -0.060758 / -0.060716), so those scenes get a fresh
        # world (0.2 s) for every rollout.
        world = self.world(scene, fresh=bool(scene.objects))
        steps = int(round(reference.duration / TIME_STEP))
        step_times = np.arange(steps + 1) * TIME_STEP
        targets = reference.positions_at(step_times)
        turns = [GRIPPER_DOWN] * (steps + 1) if reference.orientations is None else reference.orientations_at(step_times)
        openings = reference.gripper_at(step_times, scene.gripper_opening)
        positions = np.empty((steps + 1, 3))
        orientations = np.empty((steps + 1, 4))
        fingers = np.empty(steps + 1)
        forces = np.empty(steps + 1)
        frames = np.empty((steps + 1, len(scene.frames), 3))
        frame_orientations = np.empty((steps + 1, len(scene.frames), 4))
        world.reset(targets[0], openings[0], turns[0])
        events = list(reference.events)
        (positions[0], orientations[0]), fingers[0], forces[0] = world.end_effector_pose(), world.gripper_opening(), world.contact_force()
        frames[0], frame_orientations[0] = world.frame_poses()
        if observer is not None:
            observer(0.0, world)
        for step in range(1, steps + 1):
            while events and events[0][0] <= step_times[step] + 1e-9:
                time, action = events.pop(0)
                world.grasp(time) if action == "grasp" else world.release()
            world.command(targets[step], openings[step], turns[step])
            world.step()
            (positions[step], orientations[step]), fingers[step], forces[step] = world.end_effector_pose(), world.gripper_opening(), world.contact_force()
            frames[step], frame_orientations[step] = world.frame_poses()
            if observer is not None:
                observer(step_times[step], world)
        if not np.isfinite(positions).all():
            raise ExecutionError("rollout: the simulation diverged (non-finite end-effector positions)")
        forces = low_pass(forces, scene.force_filter_hz, TIME_STEP)
        frame_tilts = rotations.uprightness(frame_orientations)  # once, for every step and frame
        return _record(step_times, positions, rotations.continuous(orientations), fingers, forces, (frames, frame_tilts), scene, reference, rate)

    def close(self) -> None:
        for world in self._worlds.values():
            world.close()
        self._worlds.clear()

    def __enter__(self) -> "PyBulletBackend":
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()


def low_pass(values: np.ndarray, cutoff_hz: float, period: float) -> np.ndarray:
    """First-order low-pass filter, as a force sensor's electronics would apply (starts at 0).

    A plain loop (a few ms per rollout): `scipy.signal.lfilter` gives the same values but its
    import takes about a second, which every one-rollout process (`stlopt rollout`, an executor)
    would pay."""
    gain = 1.0 - math.exp(-2.0 * math.pi * cutoff_hz * period)
    filtered = np.empty(len(values))
    state = 0.0
    for index, value in enumerate(np.asarray(values, dtype=float).tolist()):
        state += gain * (value - state)  # y[n] = y[n-1] + gain (x[n] - y[n-1])
        filtered[index] = state
    return filtered


def _record(step_times, positions, orientations, fingers, forces, frames, scene: Scene, reference: Reference, rate: float) -> Rollout:
    times = recording_times(reference.duration, rate)
    times = times[times <= step_times[-1] + 1e-9]
    recorded = np.column_stack([np.interp(times, step_times, positions[:, axis]) for axis in range(3)])
    columns = {
        "x": recorded[:, 0],
        "y": recorded[:, 1],
        "z": recorded[:, 2],
        "gripper": np.interp(times, step_times, fingers),
        "force": np.interp(times, step_times, forces),
    }
    turned = np.column_stack([np.interp(times, step_times, orientations[:, axis]) for axis in range(4)])
    turned /= np.linalg.norm(turned, axis=1, keepdims=True)
    columns.update(zip(QUATERNION_COLUMNS, turned.T))
    columns["tilt"] = rotations.tilt(turned)
    frames, frame_tilts = frames
    for index, frame in enumerate(scene.frames):
        for axis, name in enumerate(frame.signals):
            columns[name] = np.interp(times, step_times, frames[:, index, axis])
    for index, frame in enumerate(scene.frames):
        columns[frame.tilt_signal] = np.interp(times, step_times, frame_tilts[:, index])
    error = np.linalg.norm(recorded - reference.positions_at(times), axis=1)
    return Rollout(SignalTable(times, columns, source="pybullet rollout"), error)


def pace_real_time() -> Observer:
    """An observer that slows the simulation down to wall-clock time (for the GUI)."""
    start: list[float] = []

    def observe(time: float, world: PandaWorld) -> None:
        if not start:
            start.append(clock.perf_counter() - time)
        delay = start[0] + time - clock.perf_counter()
        if delay > 0:
            clock.sleep(delay)

    return observe
