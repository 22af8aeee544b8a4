"""Scene files and placements as users write them: a scene YAML file (or a built-in scene's
name) read into a `Scene`, and `--place NAME=x,y[,z[,yaw]]` options or a task file's `place:`
mapping read into frame poses.

Built-in scenes are YAML files in `stl_lfd/sim/scenes/`. A scene file has the keys of `Scene`
(all optional except `description`); unknown keys are errors that name the key and the file.
"""

from __future__ import annotations

from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any

import stl_lfd.rotations as rotations
from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_SYMMETRY, MAX_YAW
from stl_lfd.poses import BASE_FRAME, Pose, parse_assignment, parse_pose, pose_from_values
from stl_lfd.sim.impedance import NULLSPACE_POSTURES, PANDA_TORQUE_LIMITS
from stl_lfd.sim.safety import Safety
from stl_lfd.sim.scene import HAND, Camera, Control, Scene, SceneFrame, SceneObject, check_area
from stl_lfd.sim.shapes import SHAPES, lowest_heights
from stl_lfd.spelling import spelled
from stl_lfd.yamlfile import check_keys, number, read_yaml, shown, vector


def placement_from_options(scene: Scene, texts: list[str], option: str | None = None) -> dict[str, Pose]:
    """Frame name -> pose from `NAME=x,y[,z[,yaw]]` texts (z and yaw default to the frame's);
    errors name `option` (default: the `place` setting as the user spells it)."""
    option = option or spelled("place")
    placement: dict[str, Pose] = {}
    for text in texts:
        name, pose = parse_assignment(text, option, scene.frame_poses)
        if name in placement:
            raise ConfigError(f"{option} {text}: {name} is placed twice")
        placement[name] = pose
    scene.check_placement(placement, option)
    return placement


def placement_from_yaml(scene: Scene, data: Any, path: Path | str, where: str) -> dict[str, Pose]:
    """Frame name -> pose from a mapping of `NAME: [x, y(, z(, yaw))]` or `NAME: {position:
    [x, y, z], yaw: RAD}` (z and yaw default to the frame's), checked against the scene."""
    if not isinstance(data, dict) or not data:
        raise ConfigError(f"{path}: '{where}' must map frames of the scene {scene.name} to poses (its frames: {', '.join(scene.frame_poses) or 'none'})")
    placement = {}
    for name, value in data.items():
        if name not in scene.frame_poses:
            raise ConfigError(
                f"{path}: '{where}' names {shown(name)}, which is not a frame of the scene {scene.name} (its frames: {', '.join(scene.frame_poses) or 'none'})"
            )
        if isinstance(value, list) and 2 <= len(value) <= 4:
            values = list(vector(value, len(value), path, f"{where}.{name}"))
            if len(values) == 4 and abs(values[3]) > MAX_YAW:
                raise ConfigError(f"{path}: '{where}.{name}[3]': the yaw must be in radians, within two turns either way (got {values[3]:g})")
            placement[name] = pose_from_values(values, scene.frame_poses[name])
        elif isinstance(value, dict):
            placement[name] = parse_pose(value, path, f"{where}.{name}")
        else:
            raise ConfigError(f"{path}: '{where}.{name}' must be [x, y], [x, y, z], [x, y, z, yaw] or {{position: [x, y, z], yaw: RAD}} (got {shown(value)})")
    scene.check_placement(placement, f"{path}: '{where}'")
    return placement


def builtin_scenes() -> list[str]:
    """Names of the scenes that ship with the package."""
    folder = resources.files("stl_lfd.sim") / "scenes"
    return sorted(entry.name[: -len(".yaml")] for entry in folder.iterdir() if entry.name.endswith(".yaml"))


def scene_reference(text: str, source: Path, kind: str) -> str:
    """A scene as the `kind` file `source` (a task or behaviour file) names it: a built-in
    scene's name as it is, or a scene file's absolute path, `text` read relative to `source`'s
    folder, or else, when only that exists, relative to the working directory (as task files
    written for it still name their scenes). ConfigError naming `source` when the file does not
    exist."""
    if not (text.endswith((".yaml", ".yml")) or "/" in text):
        return text
    resolved = Path(text) if Path(text).is_absolute() else source.parent / text
    if not resolved.exists() and Path(text).exists():
        resolved = Path(text)
    if not resolved.exists():
        raise ConfigError(f"{source}: 'scene' names {text}, which does not exist (paths are relative to the {kind} file)")
    if not resolved.is_file():
        raise ConfigError(f"{source}: 'scene' names {text}, which is a folder; give a scene .yaml file or a built-in scene's name")
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
    scene = replace(scene, frames=tuple(_parse_frame(name, item, path, scene) for name, item in frames.items()))
    _check_holes(scene, path)
    _check_destinations(scene, path)
    _check_clearances(scene, path)
    return scene


def _check_holes(scene: Scene, path: Path) -> None:
    """ConfigError for a `rim` outside the height of its frame's objects (the hole's walls)."""
    objects = {item.name: item for item in scene.objects}
    for frame in scene.frames:
        if frame.rim is not None:
            _check_rim(frame, [objects[name] for name in frame.objects], path)


# Where a frame's movable object goes: the key, the frames it may name, the words of the error.
DESTINATIONS = (
    ("into", lambda frame: frame.rim is not None, "another frame with a 'rim' (a hole; ", "frames with one", "goes into the hole"),
    ("onto", lambda frame: True, "another frame, the target (", "frames", "is put on the target"),
    ("inside", lambda frame: frame.interior is not None, "another frame with an 'interior' (", "frames with one", "is put inside"),
)


def _check_destinations(scene: Scene, path: Path) -> None:
    """ConfigError for an `into`, `onto` or `inside` that names no other frame of the kind it
    needs, or whose frame does not start with a movable object (what goes there)."""
    objects = {item.name: item for item in scene.objects}
    for key, fits, wanted, listed, purpose in DESTINATIONS:
        candidates = [frame.name for frame in scene.frames if fits(frame)]
        for frame in scene.frames:
            named = getattr(frame, key)
            if named is None:
                continue
            if named not in candidates or named == frame.name:
                raise ConfigError(f"{path}: 'frames.{frame.name}.{key}' must name {wanted}got {shown(named)}; {listed}: {', '.join(candidates) or 'none'})")
            if objects[frame.objects[0]].mass <= 0:
                raise ConfigError(
                    f"{path}: 'frames.{frame.name}.{key}': the frame's first object, {frame.objects[0]}, must be movable (a mass above 0): it is what {purpose}"
                )


def _check_clearances(scene: Scene, path: Path) -> None:
    """ConfigError for a `clearance` that names an unknown object or the object itself, or that
    involves a movable object no frame moves with (its pose is recorded only as a frame's first
    movable object)."""
    carried = {item.name for frame in scene.frames if (item := scene.carried_object(frame)) is not None}
    objects = {item.name: item for item in scene.objects}
    for index, item in enumerate(scene.objects):
        where = f"objects[{index}].clearance"
        unknown = [other for other in item.clearance if other != HAND and (other not in objects or other == item.name)]
        if unknown:
            raise ConfigError(f"{path}: '{where}' names {shown(unknown[0])}: it must be hand or another object ({', '.join(objects)})")
        for other in item.clearance:
            for name in (item.name, other):
                if name != HAND and objects[name].mass > 0 and name not in carried:
                    raise ConfigError(
                        f"{path}: '{where}': {name} is movable, and its pose is recorded only when a frame moves with it: list it first in a frame's 'objects'"
                    )


def _check_rim(frame: SceneFrame, walls: list[SceneObject], path: Path) -> None:
    """The rim (its height above the frame's origin) must lie between the lowest and the highest
    point of the frame's objects: a rim above the walls would count a shaft lying on top as in
    the hole, one below them never."""
    bottoms = [float(lowest_heights(item.shape, item.size, [item.position], rotations.from_euler(*item.orientation)[None])[0]) for item in walls]
    tops = [2 * item.position[2] - bottom for item, bottom in zip(walls, bottoms)]  # the shapes are symmetric about their centres
    height = frame.pose.position[2] + frame.rim
    if not min(bottoms) - 1e-9 <= height <= max(tops) + 1e-9:
        raise ConfigError(
            f"{path}: 'frames.{frame.name}.rim' ({frame.rim:g}) puts the hole's rim at z = {height:g} m, outside the frame's objects "
            f"(z {min(bottoms):g} to {max(tops):g} m); the rim is its height above the frame's origin (z = {frame.pose.position[2]:g} m)"
        )


def _parse_frame(name: Any, data: Any, path: Path, scene: Scene) -> SceneFrame:
    where = f"frames.{name}"
    if not isinstance(name, str) or not name.isidentifier() or name == BASE_FRAME:
        raise ConfigError(f"{path}: frame name {shown(name)} must be a name (letters, digits, _) other than '{BASE_FRAME}'")
    check_keys(
        data, ("position", "yaw", "objects", "area", "symmetry", "rim", "into", "onto", "interior", "inside"), path, where, required=("position", "objects")
    )
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
    if isinstance(symmetry, bool) or not isinstance(symmetry, int) or not 1 <= symmetry <= MAX_SYMMETRY:
        raise ConfigError(
            f"{path}: '{where}.symmetry' must be a whole number of yaws that give the same objects, 1 to {MAX_SYMMETRY} "
            f"(1: none, 2: a half turn, 4: a quarter turn; got {shown(symmetry)})"
        )
    rim = number(data["rim"], path, f"{where}.rim") if "rim" in data else None
    into, onto = data.get("into"), data.get("onto")
    if into is not None and not isinstance(into, str):
        raise ConfigError(f"{path}: '{where}.into' must name the frame whose hole the object goes into (got {shown(into)})")
    if onto is not None and (not isinstance(onto, str) or into is not None):
        raise ConfigError(
            f"{path}: '{where}.onto' must name the frame the object is put on, and a frame goes either into a hole or onto a target (got {shown(onto)})"
        )
    interior = None
    if "interior" in data:
        box = check_keys(data["interior"], ("lower", "upper"), path, f"{where}.interior", required=("lower", "upper"))
        low, high = (vector(box[key], 3, path, f"{where}.interior.{key}") for key in ("lower", "upper"))
        if not all(a < b for a, b in zip(low, high)):
            raise ConfigError(f"{path}: '{where}.interior' must have lower < upper in x, y and z")
        interior = (low, high)
    inside = data.get("inside")
    if inside is not None and not isinstance(inside, str):
        raise ConfigError(f"{path}: '{where}.inside' must name the frame whose interior the object is put in (got {shown(inside)})")
    frame = SceneFrame(name, pose, tuple(str(item) for item in objects), area, symmetry, pose.yaw, rim, into, onto, interior, inside)  # type: ignore[arg-type]
    check_area(frame, pose, str(path))
    return frame


# Each control setting's largest sensible value: stiffer than this, the simulated arm needs a
# finer time step than the backends take; the torque limits and finger force are the real
# robot's (the Franka Hand's peak grasp force is 140 N).
CONTROL_MAXIMA = {
    "translational_stiffness": 5000.0,
    "rotational_stiffness": 300.0,
    "damping_ratio": 5.0,
    "nullspace_stiffness": 100.0,
    "finger_force": 140.0,
}
CONTROL_KEYS = (*CONTROL_MAXIMA, "torque_limits", "nullspace_posture")
# Keys a scene file may hold for a position-controlled arm, which the compliant arm does not
# take: each is refused with the settings to give instead.
RETIRED_CONTROL_KEYS = {"position_gain": "translational_stiffness and rotational_stiffness", "arm_forces": "torque_limits"}


def _parse_control(data: Any, path: Path) -> Control:
    for key, instead in RETIRED_CONTROL_KEYS.items():
        if isinstance(data, dict) and key in data:
            raise ConfigError(f"{path}: 'control.{key}' belonged to the position-controlled arm; the arm is impedance-controlled now (set {instead})")
    check_keys(data, CONTROL_KEYS, path, "control")
    values: dict[str, Any] = {}
    for key, largest in CONTROL_MAXIMA.items():
        if key in data:
            values[key] = number(data[key], path, f"control.{key}", positive=key != "nullspace_stiffness", minimum=0.0)
            if values[key] > largest:
                raise ConfigError(f"{path}: 'control.{key}' must be at most {largest:g} (got {values[key]:g})")
    if "torque_limits" in data:
        limits = vector(data["torque_limits"], 7, path, "control.torque_limits")
        if not all(0 < limit <= real for limit, real in zip(limits, PANDA_TORQUE_LIMITS)):
            raise ConfigError(
                f"{path}: 'control.torque_limits' must be positive and at most the Panda's ({', '.join(f'{limit:g}' for limit in PANDA_TORQUE_LIMITS)} Nm)"
            )
        values["torque_limits"] = limits
    if "nullspace_posture" in data:
        if data["nullspace_posture"] not in NULLSPACE_POSTURES:
            raise ConfigError(f"{path}: 'control.nullspace_posture' must be one of {', '.join(NULLSPACE_POSTURES)} (got {shown(data['nullspace_posture'])})")
        values["nullspace_posture"] = data["nullspace_posture"]
    return Control(**values)


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
    keys = ("name", "shape", "size", "position", "orientation", "mass", "color", "friction", "rolling_friction", "clearance")
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
    for key in ("friction", "rolling_friction"):
        if key in data:
            values[key] = number(data[key], path, f"{where}.{key}", minimum=0.0)
    if "clearance" in data:
        values["clearance"] = _clearance(data["clearance"], path, where)
    return SceneObject(**values)


def _clearance(value: Any, path: Path, where: str) -> tuple[str, ...]:
    """An object's `clearance`: true (the hand), false, or a list of `hand` and object names."""
    if isinstance(value, bool):
        return (HAND,) if value else ()
    if not isinstance(value, list) or not value or not all(isinstance(name, str) for name in value) or len(set(value)) != len(value):
        raise ConfigError(f"{path}: '{where}.clearance' must be true, false or a list of distinct names: hand and other objects (got {shown(value)})")
    return tuple(value)
