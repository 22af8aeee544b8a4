"""The PyBullet backend: a compliant Franka Panda under Cartesian impedance control.

The Panda of `franka_panda/panda.urdf` (`pybullet_data`) on a floor, DIRECT mode, one physics
step per 240 Hz control step. Its arm is torque-controlled by the impedance law of
`impedance.py` (Jacobian, mass matrix and gravity and Coriolis torques from PyBullet's own
model, so compensation is exact); its fingers are position servos whose force is capped at the
scene's finger force, coupled by a gear constraint as the Franka Hand's mechanism couples them,
so that a grasp holds an object by friction alone. A force-torque sensor on the fixed joint
between flange and hand gives the wrist wrench (`world.external_wrench`). `world.simulate`
drives the rollout and records it.

A world is built once per scene and process (about 0.2 s) and restored to its saved initial
state before each rollout: the same reference always gives bit-identical signals.
"""

from __future__ import annotations

import atexit
import functools
import os
import sys
import weakref
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from stl_lfd.errors import ExecutionError
from stl_lfd.sim.backend import BackendBase, BackendOptions, Capabilities, Observer
from stl_lfd.sim.impedance import REST_POSTURE, RefreshedDynamics, impedance_torques, pose_error
from stl_lfd.sim.reference import TIME_STEP, Reference, Rollout
from stl_lfd.sim.scene import Camera, Region, Scene, SceneObject
from stl_lfd.sim.world import FrameTracker, Target, external_wrench, load_torques, simulate

END_EFFECTOR_LINK = 11  # panda_grasptarget
ARM_JOINTS = list(range(7))
FINGER_JOINTS = [9, 10]
MOVING_JOINTS = ARM_JOINTS + FINGER_JOINTS  # what the Jacobian, mass matrix and inverse dynamics take
WRIST_JOINT = 7  # panda_joint8, fixed: the flange (massless panda_link8) carries the hand
HAND_LINKS = [8, 9, 10, 11]  # the bodies beyond the wrist sensor: hand, fingers, grasp target
REGION_EDGE = 0.003  # m: how thick a region's edges are drawn
ZEROS = [0.0] * len(MOVING_JOINTS)
KEPT_WORLDS = 4  # worlds a backend keeps open (about 0.2 s to build one)
# The URDF gives the fingers soft contacts (30 kN/m): a 20 N squeeze sinks a held shaft 0.7 mm
# into them, and the shaft pivots about the fingers' axis while the hand carries it (up to 14
# degrees at some placements of the re-orient-and-insert task, so that it jams at the hole).
# The real fingertips are stiff, as MuJoCo's pads are (N/m, N s/m).
FINGER_CONTACT_STIFFNESS, FINGER_CONTACT_DAMPING = 1e6, 1e3

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
    "stepSimulation", "calculateInverseKinematics", "setJointMotorControlArray", "getLinkState", "getLinkStates", "getJointState",
    "getJointStates", "getBasePositionAndOrientation", "getBaseVelocity", "multiplyTransforms", "calculateJacobian", "calculateMassMatrix",
    "calculateInverseDynamics",
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
        client.setPhysicsEngineParameter(deterministicOverlappingPairs=1)
        self.floor = client.loadURDF("plane.urdf")
        self.robot = client.loadURDF("franka_panda/panda.urdf", useFixedBase=True)
        self._make_compliant()
        self.gains = scene.control.impedance
        self.dynamics = RefreshedDynamics(self.gains)
        self.posture = scene.control.posture()
        self.objects = {item.name: self._add_object(item) for item in scene.objects}
        self.movable = {item.name: self.objects[item.name] for item in scene.objects if item.mass > 0}
        self.masses = {item.name: item.mass for item in scene.objects}
        self.hand_masses = np.array([client.getDynamicsInfo(self.robot, link)[0] for link in HAND_LINKS])
        self.load: str | None = None  # the declared load's name
        self.frames = FrameTracker(scene)
        for region in scene.regions:
            self._add_region(region)
        for joint, angle in zip(ARM_JOINTS, REST_POSTURE):
            client.resetJointState(self.robot, joint, angle)
        self.initial_state = client.saveState()
        self.target: Target | None = None
        self._previous_jacobian: np.ndarray | None = None  # for dJ/dt dq, by differences over a step
        self._accelerations = np.zeros((len(HAND_LINKS) + 1, 3))
        self._velocities: np.ndarray | None = None  # the bodies' velocities after the last step (None: to read)
        self._started = False  # the wrist sensor holds a stale reading until the first step
        _open_worlds.add(self)

    def _make_compliant(self) -> None:
        """Torque control of the arm, force-limited fingers coupled as the hand's mechanism, the
        wrist sensor."""
        client, pb, robot = self.client, self.pb, self.robot
        # Bullet's default link damping (0.04) is not in its dynamics model: compensation would be off.
        for link in range(-1, client.getNumJoints(robot)):
            client.changeDynamics(robot, link, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0)
        # The default velocity motors hold every joint; off, the arm moves by the torques alone.
        client.setJointMotorControlArray(robot, ARM_JOINTS, pb.VELOCITY_CONTROL, forces=[0.0] * len(ARM_JOINTS))
        # Without coupling, both force-limited fingers saturate on a held object and the pair
        # drifts along the closing axis with it (18 mm measured).
        gear = client.createConstraint(robot, FINGER_JOINTS[0], robot, FINGER_JOINTS[1], pb.JOINT_GEAR, [1, 0, 0], [0, 0, 0], [0, 0, 0])
        client.changeConstraint(gear, gearRatio=-1, erp=0.1, maxForce=50)
        client.enableJointForceTorqueSensor(robot, WRIST_JOINT, True)
        for finger in FINGER_JOINTS:
            client.changeDynamics(robot, finger, contactStiffness=FINGER_CONTACT_STIFFNESS, contactDamping=FINGER_CONTACT_DAMPING)

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
        client.changeDynamics(body, -1, lateralFriction=item.friction, rollingFriction=item.rolling_friction)
        return body

    def frame_poses(self) -> tuple[np.ndarray, np.ndarray]:
        return self.frames.poses(self.object_poses())

    def _add_region(self, region: Region) -> int:
        """The region's edges, opaque: TinyRenderer, which draws the videos, draws a translucent
        box opaque, and would hide what stands inside it."""
        bars = region.edges(REGION_EDGE)
        color = [*region.color[:3], 1.0]
        visual = self.client.createVisualShapeArray(
            shapeTypes=[self.pb.GEOM_BOX] * len(bars),
            halfExtents=[list(half) for _, half in bars],
            visualFramePositions=[list(centre) for centre, _ in bars],
            rgbaColors=[color] * len(bars),
        )
        return self.client.createMultiBody(baseMass=0, baseCollisionShapeIndex=-1, baseVisualShapeIndex=visual, basePosition=[0.0, 0.0, 0.0])

    def reset(self, target: Target) -> None:
        """Restore the initial state, then place the hand at rest at `target`'s pose and the
        fingers at its opening."""
        client = self.client
        client.restoreState(self.initial_state)
        for _ in range(20):
            angles = self._inverse_kinematics(target.position, target.orientation)
            for joint, angle in zip(ARM_JOINTS, angles):
                client.resetJointState(self.robot, joint, angle, 0.0)
            if np.linalg.norm(self.hand_pose()[0] - target.position) < 1e-6:
                break
        for joint in FINGER_JOINTS:
            client.resetJointState(self.robot, joint, target.opening / 2, 0.0)
        # restoreState leaves the previous rollout's contact points (and their forces) in place
        # until the next step. Collision detection at the reset pose replaces them.
        client.performCollisionDetection()
        self.load, self.target, self._previous_jacobian, self._started = None, target, None, False
        self.dynamics.restart()
        self.posture.restart()
        self._accelerations[:] = 0.0
        self._velocities = None

    def command(self, target: Target) -> None:
        self.target = target

    def step(self) -> None:
        """Torques toward the target for the state now, then one physics step."""
        client, target = self.client, self.target
        assert target is not None, "reset first"
        joints, velocities = self._joint_states()
        jacobian = self._jacobian(joints, velocities)
        dynamics = self.dynamics.at(jacobian, lambda: np.array(client.calculateMassMatrix(self.robot, joints))[:7, :7])
        bias = np.array(client.calculateInverseDynamics(self.robot, joints, velocities, ZEROS))[:7]
        if self.load is not None:
            bias += self._load_torques(jacobian)
        arm_velocities = np.array(velocities[:7])
        previous_jacobian = self._previous_jacobian if self._previous_jacobian is not None else jacobian
        rate_term = (jacobian - previous_jacobian) @ arm_velocities / TIME_STEP  # dJ/dt dq
        position, orientation = self.hand_pose()
        arm_joints, error = np.array(joints[:7]), pose_error(position, orientation, target.position, target.orientation)
        posture = self.posture.at(arm_joints)
        torques = impedance_torques(self.gains, dynamics, bias, arm_joints, arm_velocities, error, target.twist, target.acceleration, rate_term, posture)
        client.setJointMotorControlArray(self.robot, ARM_JOINTS, self.pb.TORQUE_CONTROL, forces=torques.tolist())
        finger_force = self.scene.control.finger_force
        client.setJointMotorControlArray(
            self.robot, FINGER_JOINTS, self.pb.POSITION_CONTROL, targetPositions=[target.opening / 2] * 2, forces=[finger_force] * 2
        )
        velocities_before = self._velocities if self._velocities is not None else self._body_velocities()
        client.stepSimulation()
        self._velocities = self._body_velocities()  # read once a step: the next step starts from them
        self._accelerations = (self._velocities - velocities_before) / TIME_STEP
        self._previous_jacobian = jacobian
        self._started = True

    def _joint_states(self) -> tuple[list[float], list[float]]:
        states = self.client.getJointStates(self.robot, MOVING_JOINTS)
        return [state[0] for state in states], [state[1] for state in states]

    def _jacobian(self, joints: list[float], velocities: list[float]) -> np.ndarray:
        """`6 x 7` Jacobian of the grasp target (linear rows first)."""
        linear, angular = self.client.calculateJacobian(self.robot, END_EFFECTOR_LINK, [0.0, 0.0, 0.0], joints, velocities, ZEROS)
        return np.vstack([np.asarray(linear), np.asarray(angular)])[:, :7]

    def _load_torques(self, jacobian: np.ndarray) -> np.ndarray:
        """`7` torques that hold the declared load's weight (Franka: the load set after a grasp)."""
        assert self.load is not None
        centre = np.asarray(self.client.getBasePositionAndOrientation(self.movable[self.load])[0])
        return load_torques(jacobian, self.hand_pose()[0], centre, self.masses[self.load])

    def _bodies_beyond_wrist(self) -> tuple[np.ndarray, np.ndarray]:
        """Masses and `B x 3` centres of the hand's links and the declared load."""
        states = self.client.getLinkStates(self.robot, HAND_LINKS, computeForwardKinematics=1)
        centres = [state[0] for state in states]
        masses = self.hand_masses
        if self.load is not None:
            centres.append(self.client.getBasePositionAndOrientation(self.movable[self.load])[0])
            masses = np.append(masses, self.masses[self.load])
        return masses, np.asarray(centres)

    def _body_velocities(self) -> np.ndarray:
        """`(links + 1) x 3` velocities of the hand's links' centres and of the declared load's
        (zeros without one)."""
        states = self.client.getLinkStates(self.robot, HAND_LINKS, computeLinkVelocity=1, computeForwardKinematics=1)
        load = self.client.getBaseVelocity(self.movable[self.load])[0] if self.load is not None else (0.0, 0.0, 0.0)
        return np.array([state[6] for state in states] + [load])

    def declare_load(self, item: SceneObject | None) -> None:
        self.load = None if item is None else item.name
        self._velocities = None  # the load's row changes

    def held_frames(self) -> np.ndarray:
        contacts = self.client.getContactPoints
        held = {name for name, body in self.movable.items() if all(contacts(bodyA=self.robot, bodyB=body, linkIndexA=finger) for finger in FINGER_JOINTS)}
        return self.frames.held(held)

    def object_poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        return {name: tuple(np.asarray(value) for value in self.client.getBasePositionAndOrientation(body)) for name, body in self.movable.items()}  # type: ignore[misc]

    def _inverse_kinematics(self, position: np.ndarray, orientation: np.ndarray) -> list[float]:
        angles = self.client.calculateInverseKinematics(
            self.robot, END_EFFECTOR_LINK, list(position), list(orientation), maxNumIterations=100, residualThreshold=1e-5
        )
        return list(angles[: len(ARM_JOINTS)])

    def hand_pose(self) -> tuple[np.ndarray, np.ndarray]:
        state = self.client.getLinkState(self.robot, END_EFFECTOR_LINK, computeForwardKinematics=1)
        return np.array(state[4]), np.array(state[5])

    def gripper_opening(self) -> float:
        first, second = self.client.getJointStates(self.robot, FINGER_JOINTS)
        return first[0] + second[0]

    def wrench(self) -> np.ndarray:
        """The wrist sensor's external wrench (`world.external_wrench`), torque about the grasp
        target; zero before the first step (the sensor's reading is stale until then)."""
        if not self._started:
            return np.zeros(6)
        reaction = np.asarray(self.client.getJointState(self.robot, WRIST_JOINT)[2])
        flange = self.client.getLinkState(self.robot, WRIST_JOINT, computeForwardKinematics=1)
        turn = np.reshape(self.pb.getMatrixFromQuaternion(flange[5]), (3, 3))
        masses, centres = self._bodies_beyond_wrist()
        accelerations = self._accelerations if self.load is not None else self._accelerations[: len(HAND_LINKS)]
        # the reaction, turned into the base frame, is what the flange exerts on the hand
        return external_wrench(turn @ reaction[:3], turn @ reaction[3:], np.asarray(flange[4]), self.hand_pose()[0], masses, centres, accelerations)

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


class PyBulletBackend(BackendBase):
    """Runs references on a simulated Panda; keeps one world per scene until `close` (or the
    end of a `with` block)."""

    name = "pybullet"
    capabilities = Capabilities(simulates=True, films=True, has_gui=True, measures_force=True)

    def __init__(self, gui: bool = False) -> None:
        self.gui = gui
        self._worlds: dict[Scene, PandaWorld] = {}

    @classmethod
    def open(cls, options: BackendOptions) -> "PyBulletBackend":
        return cls(gui=options.gui)

    def world(self, scene: Scene) -> PandaWorld:
        """The world of `scene`, built on first use; the least recently used is closed beyond
        `KEPT_WORLDS` (rollouts over many object placements keep a few clients, not one each)."""
        if scene in self._worlds:
            self._worlds[scene] = self._worlds.pop(scene)  # most recently used last
        else:
            while len(self._worlds) >= KEPT_WORLDS:
                self._worlds.pop(next(iter(self._worlds))).close()
            self._worlds[scene] = PandaWorld(scene, self.gui)
        return self._worlds[scene]

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Observer | None = None) -> Rollout:
        """Execute `reference` and record the scene's signals (`Scene.recorded_signals`) at
        `rate` samples/s; `observer(time, world)` is called after the reset and after every step
        (videos, pacing the GUI)."""
        return simulate(self.world(scene), reference, scene, rate, observer, "pybullet rollout")

    def close(self) -> None:
        for world in self._worlds.values():
            world.close()
        self._worlds.clear()
