"""Behaviours: skills and gripper actions in sequence, executed as one rollout.

A behaviour file (YAML, e.g. `configs/behaviours/pick_insert.yaml`) names a scene and a list
of steps, each either a skill (`skill: NAME` with `demos: DIR` and `states: K`, or `model:
FILE`) or an action (`action: grasp|release`, `seconds`). Executing it retrieves each skill
for its expected duration plus `settle` seconds, holds the last position during actions,
closes the fingers from a grasp until the next release, and joins everything into one
reference, so the recorded signal is continuous.

A skill learned with frames (a TP-HSMM) is retrieved for the poses of the scene's frames: a
step's `frames: {MODEL_FRAME: SCENE_FRAME}` binds them, and frames it leaves out are bound to
the scene frame of the same name.

A grasp closes the fingers on the nearest movable object, which they hold by friction alone
(see `stl_lfd.sim.world`); a grasp with nothing in reach fails the rollout.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.hsmm.spread import MinimumSpread, parse_min_spread
from stl_lfd.poses import Pose
from stl_lfd.rotations import DOWN
from stl_lfd.sim import TIME_STEP, Reference
from stl_lfd.sim.scene_file import scene_reference
from stl_lfd.skill.execution import references_of
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


def behaviour_reference(
    behaviour: Behaviour, models: dict[str, HSMM], open_width: float, duration: float | None = None, poses: Mapping[str, Pose] | None = None
) -> Reference:
    """One reference for the whole behaviour; padded (holding the last pose) or cut to
    `duration` seconds when given. Skills with frames are retrieved for the scene's frame
    `poses` (name -> pose)."""
    return behaviour_references(behaviour, [models], open_width, duration, poses)[0]


def behaviour_references(
    behaviour: Behaviour, models: Sequence[dict[str, HSMM]], open_width: float, duration: float | None = None, poses: Mapping[str, Pose] | None = None
) -> list[Reference]:
    """`behaviour_reference` of N sets of the behaviour's skills (the same skills with other
    parameters), each skill step retrieved for all of them together."""
    poses = poses or {}
    retrieved = [
        references_of(
            [skills[step.name] for skills in models], [skills[step.name].expected_duration() + step.settle for skills in models], step.name, step.poses(poses)
        )
        if isinstance(step, SkillStep)
        else None
        for step in behaviour.steps
    ]
    starts = _first_positions(behaviour, models, poses) if not isinstance(behaviour.steps[0], SkillStep) else [None] * len(models)
    return [
        _joined(behaviour, [pieces[index] if pieces is not None else None for pieces in retrieved], start, open_width, duration)
        for index, start in enumerate(starts)
    ]


def _joined(behaviour: Behaviour, retrieved: list[Reference | None], start: np.ndarray | None, open_width: float, duration: float | None) -> Reference:
    """The behaviour's reference from the `retrieved` reference of each skill step (None for
    actions), starting at `start` (`1 x 3`) when it starts with an action."""
    pieces: list[np.ndarray] = []
    grippers: list[np.ndarray] = []
    skills: list[np.ndarray] = []
    states: list[np.ndarray] = []
    turns: list[np.ndarray | None] = []  # each piece's orientations (None: straight down)
    events: list[tuple[float, str]] = []
    clock, closed = 0.0, False
    for step, skill in zip(behaviour.steps, retrieved):
        if skill is not None:
            positions, names, followed, turn = skill.positions, skill.skills, skill.states, skill.orientations
        else:
            events.append((clock, step.action))
            closed = step.action == "grasp"
            positions = np.repeat(pieces[-1][-1:] if pieces else start, _steps(step.seconds), axis=0)
            names, followed = np.full(len(positions), step.action), np.zeros(len(positions), dtype=int)
            turn = None if not turns or turns[-1] is None else np.repeat(turns[-1][-1:], len(positions), axis=0)
        pieces.append(positions)
        turns.append(turn)
        grippers.append(np.full(len(positions), 0.0 if closed else open_width))
        skills.append(names)
        states.append(followed)
        clock += len(positions) * TIME_STEP
    positions, gripper, names, followed = np.concatenate(pieces), np.concatenate(grippers), np.concatenate(skills), np.concatenate(states)
    if duration is not None:
        count = _steps(duration) + 1
        if count > len(positions):  # hold the last sample
            positions, gripper, names, followed = (
                np.concatenate([values, np.repeat(values[-1:], count - len(values), axis=0)]) for values in (positions, gripper, names, followed)
            )
        positions, gripper, names, followed = positions[:count], gripper[:count], names[:count], followed[:count]
    orientations = _joined_orientations(turns, pieces, len(positions))
    times = np.arange(len(positions)) * TIME_STEP
    kept = tuple((time, action) for time, action in events if time <= times[-1])
    return Reference(times, positions, gripper, kept, names, followed, orientations)


def _joined_orientations(turns: list[np.ndarray | None], pieces: list[np.ndarray], count: int) -> np.ndarray | None:
    """The pieces' orientations joined (straight down where a piece has none), held at the end
    or cut to `count` samples; None when no piece turns the hand."""
    if all(turn is None for turn in turns):
        return None
    joined = np.concatenate([turn if turn is not None else np.tile(DOWN, (len(piece), 1)) for turn, piece in zip(turns, pieces)])
    if count > len(joined):
        joined = np.concatenate([joined, np.repeat(joined[-1:], count - len(joined), axis=0)])
    return joined[:count]


def _steps(seconds: float) -> int:
    return max(1, int(round(seconds / TIME_STEP)))


def _first_positions(behaviour: Behaviour, models: Sequence[dict[str, HSMM]], poses: Mapping[str, Pose]) -> list[np.ndarray]:
    """Where each of N sets of skills starts (`1 x 3` each): its first skill's first sample."""
    step = behaviour.skills[0]
    firsts = [skills[step.name] for skills in models]
    return [reference.positions[:1] for reference in references_of(firsts, [2 * first.sample_period_ for first in firsts], step.name, step.poses(poses))]


def reference_for(
    models: dict[str, HSMM], behaviour: Behaviour | None, open_width: float, duration: float | None = None, poses: Mapping[str, Pose] | None = None
) -> Reference:
    """The reference of a behaviour, or of the single skill in `models` when there is none;
    skills with frames for the frame `poses` of the scene."""
    return references_for([models], behaviour, open_width, duration, poses)[0]


def references_for(
    models: Sequence[dict[str, HSMM]], behaviour: Behaviour | None, open_width: float, duration: float | None = None, poses: Mapping[str, Pose] | None = None
) -> list[Reference]:
    """`reference_for` each of N sets of skills (the same skills with other parameters),
    retrieved together."""
    if behaviour is not None:
        return behaviour_references(behaviour, models, open_width, duration, poses)
    if any(len(skills) != 1 for skills in models):
        raise ConfigError(f"several skills ({', '.join(next(skills for skills in models if len(skills) != 1))}) but no behaviour to sequence them")
    return references_of([next(iter(skills.values())) for skills in models], [duration] * len(models), poses=poses)


def load_skill(path: str | Path) -> tuple[dict[str, HSMM], Behaviour | None]:
    """The skills of a model file (one skill, named `skill`) or of a behaviour file (.yaml)."""
    path = Path(path)
    if path.suffix in (".yaml", ".yml"):
        behaviour = load_behaviour(path)
        return behaviour_models(behaviour), behaviour
    return {"skill": load_model(path)}, None
