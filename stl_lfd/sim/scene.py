"""Scenes as data: what is in the world, how the robot is controlled, how it is filmed.

Built-in scenes are YAML files in `stl_lfd/sim/scenes/`; `load_scene` takes such a name or the
path of a user's YAML file. A scene file has the keys of `Scene` below (all optional except
`description`); unknown keys are errors. Regions of a specification are added at run time with
`Scene.with_regions`, so that this package never needs to read STL.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.choices import RECORDED_SIGNALS
from stl_lfd.errors import ConfigError
from stl_lfd.poses import BASE_FRAME, Pose, parse_assignment, parse_pose, pose_from_values
from stl_lfd.sim.safety import Safety
from stl_lfd.yamlfile import check_keys, number, read_yaml, shown, vector

SHAPES = ("box", "cylinder", "sphere")
REGION_COLORS = ((0.2, 0.5, 0.9, 0.3), (0.9, 0.5, 0.2, 0.3), (0.3, 0.8, 0.3, 0.3), (0.8, 0.3, 0.7, 0.3))


@dataclass(frozen=True)
class Control:
    """Joint position control of the arm: PD gain (0-1, pybullet's units) and force limits (N m)."""

    position_gain: float = 1.0
    arm_forces: tuple[float, ...] = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
    finger_force: float = 20.0


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
    for a sphere. A mass of 0 makes the object fixed to the world.
    """

    name: str
    shape: str
    size: tuple[float, ...]
    position: tuple[float, float, float]
    orientation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mass: float = 0.0
    color: tuple[float, float, float, float] = (0.6, 0.6, 0.6, 1.0)
    friction: float = 1.0

    def distance(self, point: np.ndarray, position=None, orientation=None) -> float:
        """Distance (m) from a base-frame `point` to the object's surface (0 inside), the object
        at its own pose or at `position` and `orientation` (a quaternion)."""
        position = np.asarray(self.position if position is None else position, dtype=float)
        orientation = rotations.from_euler(*self.orientation) if orientation is None else np.asarray(orientation, dtype=float)
        local = rotations.rotate(rotations.conjugate(orientation), np.asarray(point, dtype=float) - position)
        return distance_to_shape(self.shape, self.size, local)


def distance_to_shape(shape: str, size: tuple[float, ...], point: np.ndarray) -> float:
    """Distance from `point` (in the object's frame) to a box (half extents), a cylinder
    (radius, height; along z) or a sphere (radius); 0 inside."""
    if shape == "box":
        return float(np.linalg.norm(np.maximum(np.abs(point) - np.asarray(size), 0.0)))
    if shape == "cylinder":
        radius, height = size[0], size[1]
        return float(np.hypot(max(np.hypot(point[0], point[1]) - radius, 0.0), max(abs(point[2]) - height / 2, 0.0)))
    return float(max(np.linalg.norm(point) - size[0], 0.0))


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
    """

    name: str
    pose: Pose
    objects: tuple[str, ...]
    area: tuple[tuple[float, float], tuple[float, float]] | None = None
    symmetry: int = 1
    home_yaw: float = 0.0

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


@dataclass(frozen=True)
class Region:
    """An axis-aligned box drawn for viewing only (no collision): `lower` and `upper` corners."""

    name: str
    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    color: tuple[float, float, float, float] = REGION_COLORS[0]


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
        """What a rollout in this scene records: `RECORDED_SIGNALS`, each frame's position, then
        each frame's tilt."""
        return RECORDED_SIGNALS + tuple(signal for frame in self.frames for signal in frame.signals) + tuple(frame.tilt_signal for frame in self.frames)

    def placement_from_options(self, texts: list[str], option: str = "--place") -> dict[str, Pose]:
        """Frame name -> pose from `NAME=x,y[,z[,yaw]]` texts (z and yaw default to the frame's)."""
        placement: dict[str, Pose] = {}
        for text in texts:
            name, pose = parse_assignment(text, option, self.frame_poses)
            if name in placement:
                raise ConfigError(f"{option} {text}: {name} is placed twice")
            placement[name] = pose
        self.check_placement(placement, option)
        return placement

    def placement_from_yaml(self, data: Any, path: Path | str, where: str) -> dict[str, Pose]:
        """Frame name -> pose from a mapping of `NAME: [x, y(, z(, yaw))]` or `NAME: {position:
        [x, y, z], yaw: RAD}` (z and yaw default to the frame's), checked against the scene."""
        if not isinstance(data, dict) or not data:
            raise ConfigError(f"{path}: '{where}' must map frames of the scene {self.name} to poses (its frames: {', '.join(self.frame_poses) or 'none'})")
        placement = {}
        for name, value in data.items():
            if name not in self.frame_poses:
                raise ConfigError(
                    f"{path}: '{where}' names {shown(name)}, which is not a frame of the scene {self.name} (its frames: {', '.join(self.frame_poses) or 'none'})"
                )
            if isinstance(value, list) and 2 <= len(value) <= 4:
                placement[name] = pose_from_values(list(vector(value, len(value), path, f"{where}.{name}")), self.frame_poses[name])
            elif isinstance(value, dict):
                placement[name] = parse_pose(value, path, f"{where}.{name}")
            else:
                raise ConfigError(
                    f"{path}: '{where}.{name}' must be [x, y], [x, y, z], [x, y, z, yaw] or {{position: [x, y, z], yaw: RAD}} (got {shown(value)})"
                )
        self.check_placement(placement, f"{path}: '{where}'")
        return placement

    def check_placement(self, placements: Mapping[str, Pose], source: str = "--place") -> None:
        """ConfigError (naming `source`) for a frame the scene lacks or a position outside the
        frame's area."""
        frames = {frame.name: frame for frame in self.frames}
        for name, pose in placements.items():
            if name not in frames:
                raise ConfigError(f"{source}: the scene {self.name} has no object frame '{name}' (its frames: {', '.join(frames) or 'none'})")
            if not pose.turns_about_z_only:
                raise ConfigError(f"{source}: {name}: a scene turns its objects about z only; give a yaw, not an orientation")
            _check_area(frames[name], pose, source)
            self._check_above_floor(frames[name], pose, source)

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

    def place(self, placements: Mapping[str, Pose], source: str = "--place") -> "Scene":
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


def _check_area(frame: SceneFrame, pose: Pose, source: str) -> None:
    if frame.area is None:
        return
    (x_low, y_low), (x_high, y_high) = frame.area
    x, y = pose.position[0], pose.position[1]
    if not (x_low <= x <= x_high and y_low <= y <= y_high):
        raise ConfigError(
            f"{source}: {frame.name} at ({x:g}, {y:g}) is outside the area it may be placed in (x {x_low:g} to {x_high:g}, y {y_low:g} to {y_high:g})"
        )


def builtin_scenes() -> list[str]:
    """Names of the scenes that ship with the package."""
    folder = resources.files("stl_lfd.sim") / "scenes"
    return sorted(entry.name[: -len(".yaml")] for entry in folder.iterdir() if entry.name.endswith(".yaml"))


def scene_reference(text: str, source: Path, kind: str) -> str:
    """A scene as the `kind` file `source` (a task or behaviour file) names it: a built-in
    scene's name as it is, or a scene file's absolute path, `text` read relative to `source`'s
    folder (older versions read it from the working directory, which is still accepted when
    only that exists). ConfigError naming `source` when the file does not exist."""
    if not (text.endswith((".yaml", ".yml")) or "/" in text):
        return text
    resolved = Path(text) if Path(text).is_absolute() else source.parent / text
    if not resolved.exists() and Path(text).exists():
        resolved = Path(text)
    if not resolved.exists():
        raise ConfigError(f"{source}: 'scene' names {text}, which does not exist (paths are relative to the {kind} file)")
    return str(resolved.resolve())


def load_scene(name_or_path: str | Path) -> Scene:
    """A built-in scene by name (`free_space`, ...) or a scene YAML file by path."""
    text = str(name_or_path)
    if text in builtin_scenes():
        path = Path(str(resources.files("stl_lfd.sim") / "scenes" / f"{text}.yaml"))
        source = text
    elif text.endswith((".yaml", ".yml")) or Path(text).is_file():
        path = Path(text)
        if not path.is_file():
            raise ConfigError(f"{path}: scene file not found")
        source = str(path.resolve())
    else:
        raise ConfigError(f"unknown scene '{text}' (built-in: {', '.join(builtin_scenes())}; or the path of a scene .yaml file)")
    return replace(parse_scene(read_yaml(path), path), source=source)


def parse_scene(data: dict[str, Any], path: Path) -> Scene:
    """Validate the mapping read from a scene file."""
    keys = ("description", "gripper_opening", "control", "force_filter_hz", "tracking_tolerance", "grasp_distance", "camera", "objects", "frames", "safety")
    check_keys(data, keys, path, required=("description",))
    scene = Scene(name=path.stem, description=str(data["description"]))
    if "gripper_opening" in data:
        scene = replace(scene, gripper_opening=number(data["gripper_opening"], path, "gripper_opening", minimum=0.0))
    if "force_filter_hz" in data:
        scene = replace(scene, force_filter_hz=number(data["force_filter_hz"], path, "force_filter_hz", positive=True))
    for key in ("tracking_tolerance", "grasp_distance"):
        if key in data:
            scene = replace(scene, **{key: number(data[key], path, key, positive=True)})
    if "control" in data:
        scene = replace(scene, control=_parse_control(data["control"], path))
    if "camera" in data:
        scene = replace(scene, camera=_parse_camera(data["camera"], path))
    if "safety" in data:
        scene = replace(scene, safety=_parse_safety(data["safety"], path))
    objects = data.get("objects") or []
    if not isinstance(objects, list):
        raise ConfigError(f"{path}: 'objects' must be a list")
    scene = replace(scene, objects=tuple(_parse_object(item, path, index) for index, item in enumerate(objects)))
    frames = data.get("frames") or {}
    if not isinstance(frames, dict):
        raise ConfigError(f"{path}: 'frames' must map each frame's name to its pose and objects")
    return replace(scene, frames=tuple(_parse_frame(name, item, path, scene) for name, item in frames.items()))


def _parse_frame(name: Any, data: Any, path: Path, scene: Scene) -> SceneFrame:
    where = f"frames.{name}"
    if not isinstance(name, str) or not name.isidentifier() or name == BASE_FRAME:
        raise ConfigError(f"{path}: frame name {shown(name)} must be a name (letters, digits, _) other than '{BASE_FRAME}'")
    check_keys(data, ("position", "yaw", "objects", "area", "symmetry"), path, where, required=("position", "objects"))
    pose = parse_pose({key: data[key] for key in ("position", "yaw") if key in data}, path, where)
    objects = data["objects"]
    known = [item.name for item in scene.objects]
    if not isinstance(objects, list) or not objects or not all(item in known for item in objects):
        raise ConfigError(f"{path}: '{where}.objects' must list objects of the scene (got {shown(objects)}; known: {', '.join(known)})")
    area = None
    if "area" in data:
        box = check_keys(data["area"], ("lower", "upper"), path, f"{where}.area", required=("lower", "upper"))
        lower, upper = (vector(box[key], 2, path, f"{where}.area.{key}") for key in ("lower", "upper"))
        if not all(low < high for low, high in zip(lower, upper)):
            raise ConfigError(f"{path}: '{where}.area' must have lower < upper in x and y")
        area = (lower, upper)
    symmetry = data.get("symmetry", 1)
    if isinstance(symmetry, bool) or not isinstance(symmetry, int) or symmetry < 1:
        raise ConfigError(
            f"{path}: '{where}.symmetry' must be a whole number of yaws that give the same objects (1: none, 2: a half turn, 4: a quarter turn; got {shown(symmetry)})"
        )
    frame = SceneFrame(name, pose, tuple(str(item) for item in objects), area, symmetry, pose.yaw)  # type: ignore[arg-type]
    _check_area(frame, pose, str(path))
    return frame


def _parse_control(data: Any, path: Path) -> Control:
    check_keys(data, ("position_gain", "arm_forces", "finger_force"), path, "control")
    control = Control()
    if "position_gain" in data:
        gain = number(data["position_gain"], path, "control.position_gain", positive=True)
        if gain > 1:
            raise ConfigError(f"{path}: 'control.position_gain' must be in (0, 1] (got {gain:g})")
        control = replace(control, position_gain=gain)
    if "arm_forces" in data:
        control = replace(control, arm_forces=vector(data["arm_forces"], 7, path, "control.arm_forces"))
    if "finger_force" in data:
        control = replace(control, finger_force=number(data["finger_force"], path, "control.finger_force", positive=True))
    return control


def _parse_camera(data: Any, path: Path) -> Camera:
    check_keys(data, ("target", "distance", "yaw", "pitch", "width", "height", "fps"), path, "camera")
    values: dict[str, Any] = {}
    if "target" in data:
        values["target"] = vector(data["target"], 3, path, "camera.target")
    for key in ("distance", "fps"):
        if key in data:
            values[key] = number(data[key], path, f"camera.{key}", positive=True)
    for key in ("yaw", "pitch"):
        if key in data:
            values[key] = number(data[key], path, f"camera.{key}")
    for key in ("width", "height"):
        if key in data:
            values[key] = int(number(data[key], path, f"camera.{key}", minimum=16))
    return Camera(**values)


def _parse_safety(data: Any, path: Path) -> Safety:
    check_keys(data, ("workspace", "max_speed", "max_angular_speed", "max_force"), path, "safety", required=("workspace", "max_speed"))
    box = check_keys(data["workspace"], ("lower", "upper"), path, "safety.workspace", required=("lower", "upper"))
    lower, upper = (vector(box[key], 3, path, f"safety.workspace.{key}") for key in ("lower", "upper"))
    try:
        angular = number(data["max_angular_speed"], path, "safety.max_angular_speed", positive=True) if "max_angular_speed" in data else None
        force = number(data["max_force"], path, "safety.max_force", positive=True) if "max_force" in data else None
        return Safety(lower, upper, number(data["max_speed"], path, "safety.max_speed", positive=True), angular, force)
    except ValueError as error:
        raise ConfigError(f"{path}: 'safety': {error}") from None


def _parse_object(data: Any, path: Path, index: int) -> SceneObject:
    where = f"objects[{index}]"
    keys = ("name", "shape", "size", "position", "orientation", "mass", "color", "friction")
    check_keys(data, keys, path, where, required=("name", "shape", "size", "position"))
    shape = data["shape"]
    if shape not in SHAPES:
        raise ConfigError(f"{path}: '{where}.shape' must be one of {', '.join(SHAPES)} (got {shown(shape)})")
    size_length = {"box": 3, "cylinder": 2, "sphere": 1}[shape]
    values: dict[str, Any] = {
        "name": str(data["name"]),
        "shape": shape,
        "size": vector(data["size"], size_length, path, f"{where}.size"),
        "position": vector(data["position"], 3, path, f"{where}.position"),
    }
    if any(value <= 0 for value in values["size"]):
        raise ConfigError(f"{path}: '{where}.size' must be positive")
    if "orientation" in data:
        values["orientation"] = vector(data["orientation"], 3, path, f"{where}.orientation")
    if "mass" in data:
        values["mass"] = number(data["mass"], path, f"{where}.mass", minimum=0.0)
    if "color" in data:
        values["color"] = vector(data["color"], 4, path, f"{where}.color")
    if "friction" in data:
        values["friction"] = number(data["friction"], path, f"{where}.friction", minimum=0.0)
    return SceneObject(**values)
