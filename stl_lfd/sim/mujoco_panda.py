"""The MuJoCo backend: the same compliant Panda as PyBullet's, in MuJoCo.

The model (`mujoco_model.py`) is the Panda of `pybullet_data` with torque motors, force-limited
finger servos, finger pads and a wrist force-torque sensor added. Every 240 Hz control step
takes `PHYSICS_STEPS` physics steps; each applies the impedance law of `impedance.py` (its
Jacobian, operational-space inertia and nullspace refreshed once per control step, its target
carried along the reference's twist between them), with MuJoCo's own mass matrix and
gravity and Coriolis torques. `world.simulate` drives the rollout and records it.

A model is compiled once per scene and process (about 0.3 s) and reset before each rollout:
the same reference always gives bit-identical signals. Videos are rendered offscreen with
`MUJOCO_GL=egl` (the default this module sets), which needs an OpenGL library (Debian's
libegl1); a one-line error says so where none is found.
"""

from __future__ import annotations

import os
import warnings
from typing import Any

import numpy as np

from stl_lfd.errors import ExecutionError
from stl_lfd.sim.backend import BackendBase, BackendOptions, Capabilities, Observer
from stl_lfd.sim.impedance import REST_POSTURE, RefreshedDynamics, TaskDynamics, impedance_torques, pose_error
from stl_lfd.sim.mujoco_model import ARM_JOINTS, FINGER_JOINTS, FINGERS, HAND, PHYSICS_STEPS, build_model
from stl_lfd.sim.reference import TIME_STEP, Reference, Rollout
from stl_lfd.sim.scene import Camera, Scene, SceneObject
from stl_lfd.sim.world import GRAVITY, FrameTracker, Target, external_wrench, load_torques, simulate

PHYSICS_STEP = TIME_STEP / PHYSICS_STEPS
KEPT_WORLDS = 4  # compiled scenes a backend keeps (rollouts over many placements keep a few)
IK_ITERATIONS = 200
OPENGL_ADVICE = "install its OpenGL library (Debian: libegl1 for MUJOCO_GL=egl, libosmesa6 for osmesa) or set MUJOCO_GL=egl"


def _mujoco() -> Any:
    """The mujoco module, imported with offscreen rendering by EGL unless the user chose otherwise
    (it reads MUJOCO_GL once, at import, and fails there when that OpenGL library is missing)."""
    if not os.environ.get("MUJOCO_GL"):  # unset or empty
        os.environ["MUJOCO_GL"] = "egl"
    backend = os.environ["MUJOCO_GL"]
    if backend == "glfw" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise ExecutionError(f"MuJoCo cannot start with MUJOCO_GL=glfw: it needs a display, and DISPLAY is not set; {OPENGL_ADVICE}")
    try:
        with warnings.catch_warnings():  # GLFW's own complaints: the error line says what matters
            warnings.simplefilter("ignore")
            import mujoco
    except Exception as error:  # what PyOpenGL raises without its library varies (AttributeError, RuntimeError, ImportError)
        raise ExecutionError(f"MuJoCo cannot start with MUJOCO_GL={backend} ({error}); {OPENGL_ADVICE}") from None
    return mujoco


class MujocoWorld:
    """One compiled scene and its simulation state."""

    def __init__(self, scene: Scene) -> None:
        self.mj = mj = _mujoco()
        self.scene = scene
        self.model = model = build_model(scene)
        self.data = mj.MjData(model)
        self.gains = scene.control.impedance
        self.dynamics = RefreshedDynamics(self.gains)
        self.posture = scene.control.posture()
        self._scratch: Any = None  # the inverse kinematics' own state
        arm = [model.joint(name).id for name in ARM_JOINTS]
        if [model.jnt_dofadr[joint] for joint in arm] != list(range(7)) or [model.jnt_qposadr[joint] for joint in arm] != list(range(7)):
            raise ExecutionError("MuJoCo model: the arm's joints are not its first seven degrees of freedom")
        self.fingers = np.array([model.jnt_qposadr[model.joint(name).id] for name in FINGER_JOINTS])
        self.grasp_target = model.site("grasp_target").id
        self.wrist = model.site("wrist").id
        self.hand = model.body(HAND).id
        self.force_address = model.sensor_adr[model.sensor("wrist_force").id]
        self.torque_address = model.sensor_adr[model.sensor("wrist_torque").id]
        self.hand_bodies = [body for body in range(model.nbody) if self._beyond_wrist(body) and model.body_mass[body] > 0]
        self.movable = {item.name: model.body(item.name).id for item in scene.objects if item.mass > 0}
        self.finger_bodies = [model.body(name).id for name in FINGERS]
        self.masses = {item.name: item.mass for item in scene.objects}
        self.frames = FrameTracker(scene)
        self._jacobian = np.zeros((6, model.nv))
        self._jacobian_rate = np.zeros((6, model.nv))
        self._mass = np.zeros((model.nv, model.nv))
        self._acceleration = np.zeros(6)
        self._renderer: Any = None
        self.target: Target | None = None
        self.load: str | None = None
        self._wrench = np.zeros(6)

    def _beyond_wrist(self, body: int) -> bool:
        """Whether `body` is the hand or hangs from it (fingers)."""
        while body != 0:
            if body == self.hand:
                return True
            body = self.model.body_parentid[body]
        return False

    def reset(self, target: Target) -> None:
        mj, model, data = self.mj, self.model, self.data
        mj.mj_resetData(model, data)
        data.qpos[:7] = self._inverse_kinematics(target.position, target.orientation)
        data.qpos[self.fingers] = target.opening / 2
        data.ctrl[7:9] = target.opening / 2
        mj.mj_forward(model, data)
        self.target, self.load = target, None
        self.dynamics.restart()
        self.posture.restart()
        self._wrench = self._measured_wrench()

    def _inverse_kinematics(self, position: np.ndarray, orientation: np.ndarray) -> np.ndarray:
        """Arm joints that put the grasp target at `position` and `orientation`: damped least
        squares from the rest posture, drawn towards it in the nullspace, within joint limits, in
        at most `IK_ITERATIONS` steps."""
        mj, model = self.mj, self.model
        if self._scratch is None:
            self._scratch = mj.MjData(model)
        data = self._scratch
        data.qpos[:] = 0.0
        data.qpos[:7] = REST_POSTURE
        jacobian = np.zeros((6, model.nv))
        for _ in range(IK_ITERATIONS):
            mj.mj_kinematics(model, data)
            mj.mj_comPos(model, data)
            error = -pose_error(data.site_xpos[self.grasp_target], self._site_orientation(data), position, orientation)
            if np.linalg.norm(error) < 1e-10:
                break
            mj.mj_jacSite(model, data, jacobian[:3], jacobian[3:], self.grasp_target)
            arm = jacobian[:, :7]
            inverse = arm.T @ np.linalg.inv(arm @ arm.T + 1e-6 * np.eye(6))
            step = inverse @ error + (np.eye(7) - inverse @ arm) @ (0.1 * (REST_POSTURE - data.qpos[:7]))
            data.qpos[:7] = np.clip(data.qpos[:7] + step, model.jnt_range[:7, 0], model.jnt_range[:7, 1])
        return data.qpos[:7].copy()

    def _site_orientation(self, data: Any) -> np.ndarray:
        """The grasp target's orientation (quaternion x, y, z, w)."""
        quaternion = np.empty(4)
        self.mj.mju_mat2Quat(quaternion, data.site_xmat[self.grasp_target])
        return quaternion[[1, 2, 3, 0]]

    def command(self, target: Target) -> None:
        self.target = target

    def step(self) -> None:
        """Torques toward the target for the state now, held over `PHYSICS_STEPS` physics steps
        (the control runs at 240 Hz, the contacts at a finer step)."""
        mj, model, data, target = self.mj, self.model, self.data, self.target
        assert target is not None, "reset first"
        mj.mj_step1(model, data)
        dynamics, rate_term = self._task_dynamics()
        bias = data.qfrc_bias[:7].copy()
        if self.load is not None:
            centre = data.xipos[self.movable[self.load]]
            bias += load_torques(dynamics.jacobian, data.site_xpos[self.grasp_target], centre, self.masses[self.load])
        error = pose_error(data.site_xpos[self.grasp_target], self._site_orientation(data), target.position, target.orientation)
        posture = self.posture.at(data.qpos[:7])
        data.ctrl[:7] = impedance_torques(
            self.gains, dynamics, bias, data.qpos[:7], data.qvel[:7], error, target.twist, target.acceleration, rate_term, posture
        )
        data.ctrl[7:9] = target.opening / 2
        mj.mj_step2(model, data)
        for _ in range(PHYSICS_STEPS - 1):
            mj.mj_step(model, data)
        self._wrench = self._measured_wrench()  # sensors and accelerations of the last physics step
        mj.mj_kinematics(model, data)  # poses at the step's end, for the recording

    def _task_dynamics(self) -> tuple[TaskDynamics, np.ndarray]:
        """The impedance law's configuration-dependent terms, and dJ/dt dq."""
        mj, model, data = self.mj, self.model, self.data
        mj.mj_jacSite(model, data, self._jacobian[:3], self._jacobian[3:], self.grasp_target)
        mj.mj_jacDot(model, data, self._jacobian_rate[:3], self._jacobian_rate[3:], data.site_xpos[self.grasp_target], self.hand)

        def mass() -> np.ndarray:
            mj.mj_fullM(model, data, self._mass)
            return self._mass[:7, :7]

        return self.dynamics.at(self._jacobian[:, :7].copy(), mass), self._jacobian_rate[:, :7] @ data.qvel[:7]

    def _measured_wrench(self) -> np.ndarray:
        """The wrist sensor's reading turned into the external wrench (`world.external_wrench`)."""
        mj, model, data = self.mj, self.model, self.data
        turn = data.site_xmat[self.wrist].reshape(3, 3)
        force = turn @ data.sensordata[self.force_address : self.force_address + 3]
        torque = turn @ data.sensordata[self.torque_address : self.torque_address + 3]
        bodies = self.hand_bodies + ([self.movable[self.load]] if self.load is not None else [])
        accelerations = np.empty((len(bodies), 3))
        for row, body in enumerate(bodies):
            # MuJoCo's accelerations carry gravity as the base's acceleration: a - g
            mj.mj_objectAcceleration(model, data, mj.mjtObj.mjOBJ_BODY, body, self._acceleration, 0)
            accelerations[row] = self._acceleration[3:] + GRAVITY
        masses = np.append(model.body_mass[self.hand_bodies], [self.masses[self.load]] if self.load is not None else [])
        return external_wrench(force, torque, data.site_xpos[self.wrist], data.site_xpos[self.grasp_target], masses, data.xipos[bodies], accelerations)

    def hand_pose(self) -> tuple[np.ndarray, np.ndarray]:
        return self.data.site_xpos[self.grasp_target].copy(), self._site_orientation(self.data)

    def gripper_opening(self) -> float:
        return float(self.data.qpos[self.fingers].sum())

    def wrench(self) -> np.ndarray:
        return self._wrench

    def object_poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        data = self.data
        return {name: (data.xpos[body].copy(), data.xquat[body][[1, 2, 3, 0]]) for name, body in self.movable.items()}

    def frame_poses(self) -> tuple[np.ndarray, np.ndarray]:
        return self.frames.poses(self.object_poses())

    def declare_load(self, item: SceneObject | None) -> None:
        self.load = None if item is None else item.name

    def held_frames(self) -> np.ndarray:
        if not self.movable:  # free space: nothing to hold, and this runs at every step
            return self.frames.held(set())
        first, second = self.model.geom_bodyid[self.data.contact.geom1], self.model.geom_bodyid[self.data.contact.geom2]
        touched = [set(second[first == finger].tolist()) | set(first[second == finger].tolist()) for finger in self.finger_bodies]
        return self.frames.held({name for name, body in self.movable.items() if all(body in bodies for bodies in touched)})

    def render(self, camera: Camera) -> np.ndarray:
        """`height x width x 3` uint8 image from the scene camera, rendered offscreen."""
        mj = self.mj
        if self._renderer is None:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    self._renderer = mj.Renderer(self.model, camera.height, camera.width)
            except Exception as error:  # no OpenGL library, or a display-less GLFW
                backend = os.environ.get("MUJOCO_GL", "egl")
                raise ExecutionError(f"MuJoCo cannot render with MUJOCO_GL={backend} ({error}); {OPENGL_ADVICE}") from None
        view = mj.MjvCamera()
        view.type = mj.mjtCamera.mjCAMERA_FREE
        view.lookat[:] = camera.target
        view.distance = camera.distance
        view.azimuth = camera.yaw + 90.0  # PyBullet's yaw 0 looks along +y, MuJoCo's azimuth 0 along +x
        view.elevation = camera.pitch
        self._renderer.update_scene(self.data, view)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


class MujocoBackend(BackendBase):
    """Runs references on the compliant Panda in MuJoCo; keeps a compiled model per scene until
    `close` (or the end of a `with` block)."""

    name = "mujoco"
    capabilities = Capabilities(simulates=True, films=True, measures_force=True)

    def __init__(self) -> None:
        self._worlds: dict[Scene, MujocoWorld] = {}

    @classmethod
    def open(cls, options: BackendOptions) -> "MujocoBackend":
        return cls()

    def world(self, scene: Scene) -> MujocoWorld:
        """The world of `scene`, compiled on first use; the least recently used is closed beyond
        `KEPT_WORLDS`."""
        if scene in self._worlds:
            self._worlds[scene] = self._worlds.pop(scene)
        else:
            while len(self._worlds) >= KEPT_WORLDS:
                self._worlds.pop(next(iter(self._worlds))).close()
            self._worlds[scene] = MujocoWorld(scene)
        return self._worlds[scene]

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Observer | None = None) -> Rollout:
        """Execute `reference` and record the scene's signals at `rate` samples/s;
        `observer(time, world)` is called after the reset and after every control step."""
        return simulate(self.world(scene), reference, scene, rate, observer, "mujoco rollout")

    def close(self) -> None:
        for world in self._worlds.values():
            world.close()
        self._worlds.clear()
