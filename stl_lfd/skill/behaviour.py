"""Behaviours: skills and gripper actions in sequence, executed as one rollout.

A behaviour file (YAML, e.g. `configs/behaviours/pick_insert.yaml`) names a scene and a list
of steps, each either a skill (`skill: NAME` with `demos: DIR` and `states: K`, or `model:
FILE`) or an action (`action: grasp|release`, `seconds`). `stl_lfd.skill.reference` joins
them into one reference.

A skill learned with frames (a TP-HSMM) is retrieved for the poses of the scene's frames: a
step's `frames: {MODEL_FRAME: SCENE_FRAME}` binds them, and frames it leaves out are bound to
the scene frame of the same name.

A grasp closes the fingers on the nearest movable object, which they hold by friction alone
(see `stl_lfd.sim.world`); a grasp with nothing in reach fails the rollout.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.hsmm.spread import MinimumSpread, parse_min_spread
from stl_lfd.poses import Pose
from stl_lfd.sim.scene_file import scene_reference
from stl_lfd.yamlfile import check_keys, integer, number, read_yaml, shown

ACTIONS = ("grasp", "release")
DEFAULT_SETTLE = 1.0


@dataclass(frozen=True)
class SkillStep:
    name: str
    demos: Path | None
    model: Path | None
    states: int
    settle: float
    frames: tuple[tuple[str, str], ...] = ()  # (model frame, scene frame) bindings
    learn_in: tuple[str, ...] | None = None  # the frames to learn in (None: base and every sidecar frame)
    min_spread: MinimumSpread | None | str = "auto"  # as `stlopt learn --min-spread`

    def poses(self, scene_poses: Mapping[str, Pose]) -> dict[str, Pose]:
        """Model frame -> pose, from the scene's frame poses and this step's bindings."""
        bound = dict(scene_poses)
        for model_frame, scene_frame in self.frames:
            if scene_frame not in scene_poses:
                raise ConfigError(
                    f"skill {self.name}: its frame {model_frame} is bound to {scene_frame}, which the scene does not have ({', '.join(scene_poses) or 'no frames'})"
                )
            bound[model_frame] = scene_poses[scene_frame]
        return bound


@dataclass(frozen=True)
class ActionStep:
    action: str
    seconds: float


@dataclass(frozen=True)
class Behaviour:
    description: str
    scene: str
    steps: tuple[SkillStep | ActionStep, ...]
    source: Path

    @property
    def skills(self) -> list[SkillStep]:
        return [step for step in self.steps if isinstance(step, SkillStep)]


def load_behaviour(path: str | Path) -> Behaviour:
    """Read and validate a behaviour file."""
    path = Path(path)
    data = read_yaml(path)
    check_keys(data, ("description", "scene", "steps"), path, required=("scene", "steps"))
    steps = data["steps"]
    if not isinstance(steps, list) or not steps:
        raise ConfigError(f"{path}: 'steps' must be a non-empty list of skills and actions")
    parsed = tuple(_step(item, path, index) for index, item in enumerate(steps))
    names = [step.name for step in parsed if isinstance(step, SkillStep)]
    if not names:
        raise ConfigError(f"{path}: 'steps' has no skill")
    if len(set(names)) != len(names):
        raise ConfigError(f"{path}: skill names must be unique (got {', '.join(names)})")
    return Behaviour(str(data.get("description", path.stem)), scene_reference(str(data["scene"]), path, "behaviour"), parsed, path)


def _step(item: Any, path: Path, index: int) -> SkillStep | ActionStep:
    where = f"steps[{index}]"
    if isinstance(item, dict) and "action" in item:
        check_keys(item, ("action", "seconds"), path, where)
        if item["action"] not in ACTIONS:
            raise ConfigError(f"{path}: '{where}.action' must be one of {', '.join(ACTIONS)} (got {shown(item['action'])})")
        return ActionStep(item["action"], number(item.get("seconds", 1.0), path, f"{where}.seconds", positive=True))
    check_keys(item, ("skill", "demos", "model", "states", "settle", "frames", "learn_in", "min_spread"), path, where, required=("skill",))
    if ("demos" in item) == ("model" in item):
        raise ConfigError(f"{path}: '{where}' needs exactly one of 'demos' (a folder to learn from) or 'model' (a model file)")
    source_key = "demos" if "demos" in item else "model"
    source = path.parent / str(item[source_key])
    if not source.exists():
        raise ConfigError(f"{path}: '{where}.{source_key}' names {item[source_key]}, which does not exist (paths are relative to the behaviour file)")
    return SkillStep(
        name=str(item["skill"]),
        demos=source if source_key == "demos" else None,
        model=source if source_key == "model" else None,
        states=integer(item.get("states", 6), path, f"{where}.states", minimum=1),
        settle=number(item.get("settle", DEFAULT_SETTLE), path, f"{where}.settle", minimum=0.0),
        frames=_bindings(item.get("frames", {}), path, f"{where}.frames"),
        learn_in=_frame_names(item["learn_in"], path, f"{where}.learn_in") if "learn_in" in item else None,
        min_spread=_min_spread(item.get("min_spread", "auto"), path, f"{where}.min_spread"),
    )


def _bindings(data: Any, path: Path, where: str) -> tuple[tuple[str, str], ...]:
    if not isinstance(data, dict) or not all(isinstance(key, str) and isinstance(value, str) for key, value in data.items()):
        raise ConfigError(f"{path}: '{where}' must map the model's frames to the scene's (got {shown(data)})")
    return tuple(data.items())


def _frame_names(data: Any, path: Path, where: str) -> tuple[str, ...]:
    if not isinstance(data, list) or not data or not all(isinstance(name, str) for name in data):
        raise ConfigError(f"{path}: '{where}' must list the frames to learn the skill in, such as [base, holder] (got {shown(data)})")
    return tuple(data)


def _min_spread(data: Any, path: Path, where: str) -> MinimumSpread | None | str:
    try:
        return parse_min_spread(",".join(str(value) for value in data) if isinstance(data, list) else str(data), f"'{where}'")
    except ModelError as error:
        raise ConfigError(f"{path}: {error}") from None


def behaviour_models(behaviour: Behaviour) -> dict[str, HSMM]:
    """The model of every skill, learned from its demonstrations or loaded."""
    return {step.name: _model(step) for step in behaviour.skills}


def _model(step: SkillStep) -> HSMM:
    if step.demos is None:
        return load_model(step.model)
    frames = list(step.learn_in) if step.learn_in is not None else None
    return learn_from_folder(step.demos, step.states, frames=frames, min_spread=step.min_spread)[0]


def load_skill(path: str | Path) -> tuple[dict[str, HSMM], Behaviour | None]:
    """The skills of a model file (one skill, named `skill`) or of a behaviour file (.yaml)."""
    path = Path(path)
    if path.suffix in (".yaml", ".yml"):
        behaviour = load_behaviour(path)
        return behaviour_models(behaviour), behaviour
    return {"skill": load_model(path)}, None
