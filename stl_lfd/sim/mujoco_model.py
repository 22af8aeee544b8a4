"""The MuJoCo model of a scene: the Panda of `pybullet_data`'s `franka_panda/panda.urdf` (nothing
downloaded), completed through `MjSpec` with what the URDF lacks, on a floor with the scene's
objects and regions.

Added to the URDF's arm:
- torque motors on the seven arm joints, limited to the scene's torque limits, and the rotor
  inertia (armature, 0.1 kg m^2) that the URDF leaves out;
- position servos on the fingers whose force is capped at the scene's finger force, and a pad on
  each fingertip's inner face (condim 6: torsional and rolling friction, so that a held shaft
  does not pivot about the fingers' axis); the fingers do not collide with each other;
- a `grasp_target` site 0.105 m along the hand's z (where PyBullet's link 11 is) and a
  `wrist` site at the hand's origin carrying a force and a torque sensor: what the flange
  (`panda_link8`) exerts on the hand.

Contacts are stiffer than MuJoCo's defaults (solref 5 ms): with the defaults, a 20 N squeeze
sinks 2 mm into a 50 g shaft, since contact stiffness scales with the lighter body's mass.
"""

from __future__ import annotations

import functools
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.sim.reference import TIME_STEP
from stl_lfd.sim.scene import Region, Scene, SceneObject

PHYSICS_STEPS = 2  # per 240 Hz control step: 1/480 s (1/960 gives the same signals at 0.7x the speed)
ARM_JOINTS = tuple(f"panda_joint{index}" for index in range(1, 8))
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
FINGERS = ("panda_leftfinger", "panda_rightfinger")
HAND = "panda_hand"
GRASP_TARGET_OFFSET = 0.105  # m along the hand's z (the URDF's panda_grasptarget_hand joint)
ARMATURE = 0.1  # kg m^2 on each arm joint, as MuJoCo Menagerie's Panda
FINGER_GAIN = 5000.0  # N/m: the servo saturates at the finger force within a few mm of squeeze
FINGER_MASS = 0.1  # kg (URDF), for a critically damped finger servo
CONTACT_REFERENCE = (0.005, 1.0)  # solref: time constant (s), damping ratio
CONTACT_IMPEDANCE = (0.95, 0.99, 0.001, 0.5, 2.0)  # solimp
TORSIONAL_FRICTION = 0.005  # m, with condim 6: a held shaft does not pivot about the fingers' axis
ROLLING_FRICTION = 0.0001  # m, the robot's and the floor's (objects have their own)
PAD_HALF_SIZE = (0.0087, 0.0021, 0.009)  # m: a pad on each fingertip's inner face (finger frame)


@functools.lru_cache(maxsize=1)
def panda_urdf() -> Path:
    """A copy of `pybullet_data`'s Panda folder whose mesh paths MuJoCo can resolve (it does not
    know `package://`); made once per process, removed at exit."""
    import atexit

    import pybullet_data

    folder = Path(tempfile.mkdtemp(prefix="stlopt-panda-"))
    atexit.register(shutil.rmtree, folder, True)
    target = folder / "franka_panda"
    shutil.copytree(Path(pybullet_data.getDataPath()) / "franka_panda", target)
    urdf = target / "panda.urdf"
    urdf.write_text(re.sub(r"package://", "", urdf.read_text()))
    return urdf


def build_model(scene: Scene) -> Any:
    """The compiled `mujoco.MjModel` of `scene` (bodies named as the scene's objects)."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(panda_urdf()))
    spec.compiler.fusestatic = False  # keep the hand a body of its own: the sensor sits between it and the flange
    options = spec.option
    options.timestep = TIME_STEP / PHYSICS_STEPS
    options.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    options.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    options.impratio = 10.0  # friction stiffer than normal contact: no creep in a grasp
    options.noslip_iterations = 5
    for name in ARM_JOINTS:
        spec.joint(name).armature = ARMATURE
    _add_hand(spec, scene)
    _add_actuators(spec, scene)
    floor = spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], rgba=[0.9, 0.9, 0.9, 1])
    _contact(floor, 1.0)
    spec.worldbody.add_light(pos=[0.5, 0.0, 2.0], dir=[0.0, 0.0, -1.0], diffuse=[0.8, 0.8, 0.8])
    for item in scene.objects:
        _add_object(spec, item)
    for region in scene.regions:
        _add_region(spec, region)
    return spec.compile()


def _contact(geom: Any, friction: float, rolling: float = ROLLING_FRICTION) -> None:
    geom.condim = 6
    geom.friction = [friction, TORSIONAL_FRICTION, rolling]
    geom.solref = list(CONTACT_REFERENCE)
    geom.solimp = list(CONTACT_IMPEDANCE)


def _add_hand(spec: Any, scene: Scene) -> None:
    import mujoco

    for name, side in zip(FINGERS, (1.0, -1.0)):
        finger = spec.body(name)
        for geom in finger.geoms:
            _contact(geom, 1.0)
        pad = finger.add_geom(name=f"{name}_pad", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(PAD_HALF_SIZE), rgba=[0.2, 0.2, 0.2, 1])
        pad.pos = [0.0, side * (PAD_HALF_SIZE[1] - 0.0002), 0.045]  # 0.2 mm proud of the finger's mesh
        pad.mass = 0.0  # the URDF's inertial stays the finger's
        _contact(pad, 1.0)
    spec.add_exclude(bodyname1=FINGERS[0], bodyname2=FINGERS[1])
    hand = spec.body(HAND)
    hand.add_site(name="grasp_target", pos=[0.0, 0.0, GRASP_TARGET_OFFSET], size=[0.005, 0.005, 0.005])
    hand.add_site(name="wrist", pos=[0.0, 0.0, 0.0], size=[0.005, 0.005, 0.005])
    spec.add_sensor(name="wrist_force", type=mujoco.mjtSensor.mjSENS_FORCE, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="wrist")
    spec.add_sensor(name="wrist_torque", type=mujoco.mjtSensor.mjSENS_TORQUE, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="wrist")


def _add_actuators(spec: Any, scene: Scene) -> None:
    import mujoco

    for name, limit in zip(ARM_JOINTS, scene.control.torque_limits):
        motor = spec.add_actuator(name=f"{name}_motor", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        motor.set_to_motor()
        motor.ctrllimited = 1
        motor.ctrlrange = [-limit, limit]
    for name in FINGER_JOINTS:
        servo = spec.add_actuator(name=f"{name}_servo", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        servo.set_to_position(kp=FINGER_GAIN, kv=2.0 * np.sqrt(FINGER_GAIN * FINGER_MASS))
        servo.ctrllimited = 1
        servo.ctrlrange = [0.0, 0.04]
        servo.forcelimited = 1
        servo.forcerange = [-scene.control.finger_force, scene.control.finger_force]


def _add_object(spec: Any, item: SceneObject) -> None:
    import mujoco

    orientation = rotations.from_euler(*item.orientation)
    body = spec.worldbody.add_body(name=item.name, pos=list(item.position), quat=[orientation[3], *orientation[:3]])
    if item.mass > 0:
        body.add_freejoint(name=f"{item.name}_free")
    geom = body.add_geom(name=item.name, rgba=list(item.color))
    if item.shape == "box":
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_BOX, list(item.size)
    elif item.shape == "cylinder":
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_CYLINDER, [item.size[0], item.size[1] / 2.0, 0.0]  # MuJoCo: half height
    else:
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_SPHERE, [item.size[0], 0.0, 0.0]
    _contact(geom, item.friction, item.rolling_friction)
    if item.mass > 0:
        geom.mass = item.mass


def _add_region(spec: Any, region: Region) -> None:
    """A translucent box for viewing only: it collides with nothing."""
    import mujoco

    lower, upper = np.asarray(region.lower), np.asarray(region.upper)
    spec.worldbody.add_geom(
        name=f"region_{region.name}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=list((lower + upper) / 2), size=list((upper - lower) / 2),
        rgba=list(region.color), contype=0, conaffinity=0,
    )  # fmt: skip
