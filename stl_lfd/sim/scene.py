"""Scenes as data: what is in the world, how the robot is controlled, how it is filmed.

Reading scene files and placements is `scene_file.py`'s. Regions of a specification are added
at run time with `Scene.with_regions`, so that this package never needs to read STL.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.choices import RECORDED_SIGNALS
from stl_lfd.errors import ConfigError
from stl_lfd.poses import Pose
from stl_lfd.sim.impedance import PANDA_TORQUE_LIMITS, Impedance, NullspacePosture
from stl_lfd.sim.safety import Safety
from stl_lfd.sim.shapes import distance_to_shape
from stl_lfd.spelling import spelled

# m: rolling resistance of an object by default, about that of a metal shaft on a wooden table
ROLLING_FRICTION = 0.001
HAND = "hand"  # what `SceneObject.clearance` calls the hand, its fingers and what they hold
REGION_COLORS = ((0.2, 0.5, 0.9, 0.3), (0.9, 0.5, 0.2, 0.3), (0.3, 0.8, 0.3, 0.3), (0.8, 0.3, 0.7, 0.3))


@dataclass(frozen=True)
class Control:
    """The compliant arm (Cartesian impedance on the torque interface, `impedance.py`) and the
    force-controlled fingers. Defaults are close to the real robot's example controllers.

    Attributes:
        translational_stiffness: N/m on the hand's position error.
        rotational_stiffness: Nm/rad on its orientation error.
        damping_ratio: 1 for critical damping.
        nullspace_stiffness: Nm/rad of the posture spring in the task's nullspace.
        torque_limits: Nm, joints 1-7 (the Panda's: 87 for 1-4, 12 for 5-7).
        finger_force: N each finger squeezes with when it closes on an object (the Franka
            Hand grasps with up to 70 N continuous).
        nullspace_posture: what the nullspace spring pulls towards: `rest`, a fixed posture,
            or `reference`, the arm's inverse kinematics for the reference (`NullspacePosture`).
    """

    translational_stiffness: float = 400.0
    rotational_stiffness: float = 20.0
    damping_ratio: float = 1.0
    nullspace_stiffness: float = 10.0
    torque_limits: tuple[float, ...] = PANDA_TORQUE_LIMITS
    finger_force: float = 20.0
    nullspace_posture: str = "rest"

    @property
    def impedance(self) -> Impedance:
        return Impedance(self.translational_stiffness, self.rotational_stiffness, self.damping_ratio, self.nullspace_stiffness, self.torque_limits)

    def posture(self) -> NullspacePosture:
        return NullspacePosture(self.nullspace_posture)


@dataclass(frozen=True)
class Camera:
    """A fixed camera looking at `target` (metres) from `distance`, `yaw` and `pitch` (degrees)."""

    target: tuple[float, float, float] = (0.5, 0.0, 0.3)
    distance: float = 1.2
    yaw: float = 50.0
    pitch: float = -30.0
    width: int = 480
    height: int = 360
    fps: float = 24.0


@dataclass(frozen=True)
class SceneObject:
    """A rigid body of the scene.

    `size` holds half extents (x, y, z) for a box, (radius, height) for a cylinder and (radius,)
    for a sphere. A mass of 0 makes the object fixed to the world. `friction` is the sliding
    friction coefficient; `rolling_friction` (m) the rolling resistance, the lever arm of the
    torque that opposes rolling (a dropped shaft comes to rest instead of rolling on forever).
    `clearance` names what the object's distance is recorded to (`HAND`, other objects):
    `clearance_signals`.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    position: tuple[float, float, float]
    orientation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mass: float = 0.0
    color: tuple[float, float, float, float] = (0.6, 0.6, 0.6, 1.0)
    friction: float = 1.0
    rolling_friction: float = ROLLING_FRICTION
    clearance: tuple[str, ...] = ()

    @property
    def clearance_signals(self) -> tuple[str, ...]:
        """The signed distance (m) of the object to each of its `clearance`: `NAME_clearance` to
        the hand, the fingers and what they hold, `NAME_clearance_OTHER` to another object
        (`stl_lfd.sim.clearance`)."""
        return tuple(f"{self.name}_clearance" if other == HAND else f"{self.name}_clearance_{other}" for other in self.clearance)

    def distance(self, point: np.ndarray, position=None, orientation=None) -> float:
        """Distance (m) from a base-frame `point` to the object's surface (0 inside), the object
        at its own pose or at `position` and `orientation` (a quaternion)."""
        position = np.asarray(self.position if position is None else position, dtype=float)
        orientation = rotations.from_euler(*self.orientation) if orientation is None else np.asarray(orientation, dtype=float)
        local = rotations.rotate(rotations.conjugate(orientation), np.asarray(point, dtype=float) - position)
        return distance_to_shape(self.shape, self.size, local)


@dataclass(frozen=True)
class SceneFrame:
    """A named object pose that skills refer to (a TP-HSMM frame) and that can be placed.

    Attributes:
        name: the frame's name (`shaft`); rollouts record its origin as `NAME_x, NAME_y, NAME_z`
            and the angle between its first object's z axis (a cylinder's axis) and the
            vertical as `NAME_tilt` (0 to pi/2: an axis has no direction).
        pose: where the frame is (position in metres, yaw in radians about z).
        objects: the scene objects that move with it, rigidly.
        area: `(lower, upper)` x-y corners the frame's position may be placed in, or None.
        symmetry: how many yaws a full turn about z brings the frame's objects back to
            themselves (2: a lying cylinder, 4: a square hole; 1: none). A placement's yaw is
            taken as the equivalent yaw nearest `home_yaw`, so skills see the object as it was
            demonstrated.
        home_yaw: the yaw of the frame in the scene file (rad).
        rim: the frame holds a hole whose axis is the frame's vertical through its origin and
            whose rim lies `rim` metres above the origin (None: no hole).
        into: the frame (one with a `rim`) whose hole this frame's movable object goes into;
            rollouts then record `NAME_depth` and `NAME_offset` (None: no hole to go into).
        onto: the frame whose origin is the target point this frame's movable object is put on
            (a spot on a shelf's top, the centre of a block's top face); rollouts then record
            `NAME_height`, `NAME_dx`, `NAME_dy` and `NAME_offset` (None: no such target).
        interior: `(lower, upper)` corners of a box relative to the frame's origin, along its
            first object's axes: the space inside a container (a tray between its walls, a
            drawer), or None.
        inside: the frame (one with an `interior`) this frame's movable object is put inside;
            rollouts then record `NAME_inside` (None: none).
    """

    name: str
    pose: Pose
    objects: tuple[str, ...]
    area: tuple[tuple[float, float], tuple[float, float]] | None = None
    symmetry: int = 1
    home_yaw: float = 0.0
    rim: float | None = None
    into: str | None = None
    onto: str | None = None
    interior: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    inside: str | None = None

    def equivalent(self, pose: Pose) -> Pose:
        """`pose` with its yaw turned by a multiple of the symmetry's angle to lie within half of
        that angle of `home_yaw`: the same physical placement of the frame's objects."""
        step = 2.0 * math.pi / self.symmetry
        turns = round((pose.yaw - self.home_yaw) / step)
        return pose if turns == 0 else Pose(pose.position, pose.yaw - turns * step)

    @property
    def signals(self) -> tuple[str, str, str]:
        return (f"{self.name}_x", f"{self.name}_y", f"{self.name}_z")

    @property
    def tilt_signal(self) -> str:
        """The recorded angle (rad, 0 to pi/2) between the z axis of the frame's first object (a
        cylinder's axis) and the vertical."""
        return f"{self.name}_tilt"

    @property
    def motion_signals(self) -> tuple[str, str]:
        """For a frame that moves with a movable object: its origin's speed (m/s) and whether
        both fingers touch the object (1 or 0)."""
        return (f"{self.name}_speed", f"{self.name}_held")

    @property
    def orientation_signals(self) -> tuple[str, str, str, str]:
        """For a frame that moves with a movable object: its object's orientation, a unit
        quaternion in the base frame, scalar last (what a grasp model learns the object's pose
        in the hand from)."""
        qx, qy, qz, qw = (f"{self.name}_{component}" for component in rotations.QUATERNION_COLUMNS)
        return (qx, qy, qz, qw)

    @property
    def hole_signals(self) -> tuple[str, str]:
        """For a frame that goes `into` a hole: how deep its object's lowest point is below the
        rim (m, negative above it), and the horizontal distance (m) from the object's centre
        to the hole's axis."""
        return (f"{self.name}_depth", f"{self.name}_offset")

    @property
    def target_signals(self) -> tuple[str, str, str, str]:
        """For a frame put `onto` a target: the height (m) of its object's lowest point above the
        target's origin (0 resting on a surface there, negative below it), its object's centre's
        offset from the origin along the x and y axes of the target's first object (m), and
        their distance."""
        return (f"{self.name}_height", f"{self.name}_dx", f"{self.name}_dy", f"{self.name}_offset")

    @property
    def inside_signal(self) -> str:
        """For a frame put `inside` another's interior: how far its whole object is inside that
        box (m: the least distance from the object to the box's faces; negative by how far it
        sticks out)."""
        return f"{self.name}_inside"


@dataclass(frozen=True)
class Region:
    """An axis-aligned box drawn for viewing only (no collision): `lower` and `upper` corners."""

    name: str
    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    color: tuple[float, float, float, float] = REGION_COLORS[0]

    def edges(self, thickness: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """The box's 12 edges as bars `thickness` thick: `(centre, half extents)` each (a
        wireframe, for renderers that draw a translucent box opaque)."""
        lower, upper = np.asarray(self.lower, dtype=float), np.asarray(self.upper, dtype=float)
        middle, half = (lower + upper) / 2, (upper - lower) / 2
        bars = []
        for axis in range(3):
            others = [other for other in range(3) if other != axis]
            for first in (lower, upper):
                for second in (lower, upper):
                    centre = middle.copy()
                    centre[others[0]], centre[others[1]] = first[others[0]], second[others[1]]
                    extent = np.full(3, thickness / 2)
                    extent[axis] = half[axis] + thickness / 2
                    bars.append((centre, extent))
        return bars


@dataclass(frozen=True)
class Scene:
    """Everything a backend needs to set up and run the world.

    Attributes:
        name: the scene's name (its file stem).
        description: one line for humans.
        gripper_opening: finger opening (m) when the reference does not command the gripper.
        control: arm and finger control settings.
        force_filter_hz: cut-off of the first-order low-pass that models the force sensor.
        tracking_tolerance: worst end-effector error (m) beyond which a rollout warns that the
            reference was not followed (typically a target outside the workspace).
        grasp_distance: how far (m) from the grasp-target link a movable object may be for a
            `grasp` event to take it.
        camera: the viewpoint of videos and of the GUI.
        objects: rigid bodies besides the robot and the floor.
        frames: object poses that skills refer to; `place` moves them with their objects.
        regions: boxes drawn for viewing.
        safety: the workspace box and maximum speed every reference must respect before it
            leaves stlopt (external command, `stlopt ask`); None when the scene declares none.
        source: the built-in name or the absolute path the scene was loaded from.
    """

    name: str
    description: str
    gripper_opening: float = 0.08
    control: Control = field(default_factory=Control)
    force_filter_hz: float = 10.0
    tracking_tolerance: float = 0.01
    grasp_distance: float = 0.03
    camera: Camera = field(default_factory=Camera)
    objects: tuple[SceneObject, ...] = ()
    frames: tuple[SceneFrame, ...] = ()
    regions: tuple[Region, ...] = ()
    safety: Safety | None = None
    source: str = field(default="", repr=False, compare=False)

    @property
    def frame_poses(self) -> dict[str, Pose]:
        """Frame name -> its pose."""
        return {frame.name: frame.pose for frame in self.frames}

    @property
    def recorded_signals(self) -> tuple[str, ...]:
        """What a rollout in this scene records: `RECORDED_SIGNALS`, each frame's position, each
        frame's tilt, then the speed and held flag of each frame that moves with a movable object
        (`moving_frames`), the depth and offset of each frame that goes into a hole, the height
        and offsets of each frame put onto a target, the orientation of each frame that moves
        with a movable object, how far inside its container each frame put `inside` one is, and
        last the clearances of each object declared with them."""
        return (
            RECORDED_SIGNALS
            + tuple(signal for frame in self.frames for signal in frame.signals)
            + tuple(frame.tilt_signal for frame in self.frames)
            + tuple(signal for frame in self.moving_frames for signal in frame.motion_signals)
            + tuple(signal for frame in self.frames if frame.into for signal in frame.hole_signals)
            + tuple(signal for frame in self.frames if frame.onto for signal in frame.target_signals)
            + tuple(signal for frame in self.moving_frames for signal in frame.orientation_signals)
            + tuple(frame.inside_signal for frame in self.frames if frame.inside)
            + tuple(signal for item in self.objects for signal in item.clearance_signals)
        )

    def carried_object(self, frame: SceneFrame) -> SceneObject | None:
        """The movable object `frame` moves with (the first it lists), or None."""
        objects = {item.name: item for item in self.objects}
        return next((objects[name] for name in frame.objects if objects[name].mass > 0), None)

    def origin_in_object(self, frame: SceneFrame) -> np.ndarray:
        """`3`: where `frame`'s origin is in the frame of its carried object (`carried_object`),
        which it moves with rigidly."""
        item = self.carried_object(frame)
        assert item is not None, f"frame {frame.name} moves with no object"
        turn = rotations.from_euler(*item.orientation)
        return rotations.rotate(rotations.conjugate(turn), np.asarray(frame.pose.position) - np.asarray(item.position))

    @property
    def moving_frames(self) -> tuple[SceneFrame, ...]:
        """The frames that move with a movable object."""
        return tuple(frame for frame in self.frames if self.carried_object(frame) is not None)

    def check_placement(self, placements: Mapping[str, Pose], source: str | None = None) -> None:
        """ConfigError (naming `source`, by default the `place` setting) for a frame the scene
        lacks or a position outside the frame's area."""
        source = source or spelled("place")
        frames = {frame.name: frame for frame in self.frames}
        for name, pose in placements.items():
            if name not in frames:
                raise ConfigError(f"{source}: the scene {self.name} has no object frame '{name}' (its frames: {', '.join(frames) or 'none'})")
            if not pose.turns_about_z_only:
                raise ConfigError(f"{source}: {name}: a scene turns its objects about z only; give a yaw, not an orientation")
            check_area(frames[name], pose, source)
            self._check_above_floor(frames[name], pose, source)
            if self.safety is not None and pose.position[2] > self.safety.upper[2]:
                raise ConfigError(
                    f"{source}: {name} at z = {pose.position[2]:g} is above the scene's workspace (its top at z = {self.safety.upper[2]:g}); heights are in metres"
                )

    def _check_above_floor(self, frame: SceneFrame, pose: Pose, source: str) -> None:
        """ConfigError when placing `frame` at `pose` puts one of its objects' centres below the floor."""
        objects = {item.name: item for item in self.objects}
        for name in frame.objects:
            height = pose.position[2] + objects[name].position[2] - frame.pose.position[2]
            if height < 0:
                raise ConfigError(
                    f"{source}: {frame.name} at z = {pose.position[2]:g} puts {name} below the floor (its centre at z = {height:g}; the scene has it at {objects[name].position[2]:g})"
                )

    def frame_object_orientation(self, frame: SceneFrame) -> np.ndarray:
        """The orientation (quaternion) of the frame's first object, or of the frame itself when
        it has none."""
        objects = {item.name: item for item in self.objects}
        if not frame.objects:
            return frame.pose.orientation
        return rotations.from_euler(*objects[frame.objects[0]].orientation)

    def place(self, placements: Mapping[str, Pose], source: str | None = None) -> "Scene":
        """A copy with frames moved to `placements` (name -> pose), their objects with them;
        checked as `check_placement` does."""
        self.check_placement(placements, source)
        frames = {frame.name: frame for frame in self.frames}
        objects = {item.name: item for item in self.objects}
        for name, placed in placements.items():
            frame = frames[name]
            pose = frame.equivalent(placed)
            for object_name in frame.objects:
                item = objects[object_name]
                local = frame.pose.from_base(np.array([item.position]))
                position = tuple(float(v) for v in pose.to_base(local)[0])
                yaw = item.orientation[2] + pose.yaw - frame.pose.yaw
                objects[object_name] = replace(item, position=position, orientation=(item.orientation[0], item.orientation[1], yaw))
            frames[name] = replace(frame, pose=pose)
        return replace(self, objects=tuple(objects.values()), frames=tuple(frames.values()))

    def with_regions(self, boxes: Mapping[str, Mapping[str, tuple[float, float]]]) -> "Scene":
        """A copy that also draws `boxes` (name -> {signal: (lo, hi)}); boxes need x, y and z."""
        regions = []
        for index, (name, box) in enumerate(boxes.items()):
            if not all(axis in box for axis in "xyz"):
                continue
            lower = tuple(float(box[axis][0]) for axis in "xyz")
            upper = tuple(float(box[axis][1]) for axis in "xyz")
            regions.append(Region(name, lower, upper, REGION_COLORS[index % len(REGION_COLORS)]))
        return replace(self, regions=tuple(regions))


def check_area(frame: SceneFrame, pose: Pose, source: str) -> None:
    if frame.area is None:
        return
    (x_low, y_low), (x_high, y_high) = frame.area
    x, y = pose.position[0], pose.position[1]
    if not (x_low <= x <= x_high and y_low <= y <= y_high):
        raise ConfigError(
            f"{source}: {frame.name} at ({x:g}, {y:g}) is outside the area it may be placed in (x {x_low:g} to {x_high:g}, y {y_low:g} to {y_high:g})"
        )
