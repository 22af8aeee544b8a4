"""The one way skills become a reference to execute: one skill model, or the skills of a
behaviour joined with its gripper actions, each retrieved for the poses of the scene's frames.

`build_references` builds the references of N sets of the same skills (with other parameters)
at once, retrieving each skill for all of them together; `build_reference` is the same for one
set. `PlacedSkill.reference(s)` (skills in a placed scene, as every command and the optimiser's
objective execute them) calls these.

A behaviour's reference: each skill retrieved for its expected duration plus its step's
`settle` seconds and eased in from where the step before left the hand (`eased_in`: a jump
where skills join jerks the arm, and the wrist reads a spike), the last position held during
actions, the fingers closing (at `GRIPPER_SPEED`) from a grasp until the next release,
which opens them,
everything joined into one reference (padded by holding the last sample, or cut, to
`duration` when given), so that the recorded signal is continuous.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM, TPHSMM, Trajectory
from stl_lfd.hsmm.retrieval import retrieve_batch
from stl_lfd.poses import BASE_FRAME, Pose
from stl_lfd.rotations import DOWN
from stl_lfd.sim import SIMULATION_RATE, TIME_STEP, Reference
from stl_lfd.skill.behaviour import Behaviour, SkillStep

POSITION_SIGNALS = ("x", "y", "z")
OPEN_WIDTH = 0.08  # m: the fingers' opening where a behaviour has no scene to say it
# m/s: how fast the commanded opening closes at a grasp (the Franka Hand's fastest): fingers told
# to close at once strike the object, and the wrist reads the blow. A release opens at once: the
# fingers stand on the object, a fraction of a millimetre from letting it go.
GRIPPER_SPEED = 0.1
EASE_SECONDS = 1.0  # s: a skill's start moves to where the step before left the hand over this


def build_reference(
    skills: dict[str, HSMM],
    behaviour: Behaviour | None = None,
    open_width: float = OPEN_WIDTH,
    duration: float | None = None,
    poses: Mapping[str, Pose] | None = None,
) -> Reference:
    """The reference of `skills` (skill name -> model): sequenced by `behaviour`, or the single
    skill when there is none. See `references`."""
    return build_references([skills], behaviour, open_width, duration, poses)[0]


def build_references(
    skill_sets: Sequence[dict[str, HSMM]],
    behaviour: Behaviour | None = None,
    open_width: float = OPEN_WIDTH,
    duration: float | None = None,
    poses: Mapping[str, Pose] | None = None,
) -> list[Reference]:
    """The reference of each of N sets of the same skills (skill name -> model), retrieved
    together.

    Args:
        behaviour: sequences the skills with gripper actions; None for a single skill.
        open_width: the fingers' opening (m) while they are open (a behaviour's).
        duration: seconds of every reference (None: the skills' expected durations).
        poses: the scene's frame poses (name -> pose), for skills learned with frames.

    Raises:
        ConfigError: several skills without a behaviour, or a frame the scene lacks.
        ModelError: a model without the position signals x, y, z.
    """
    if behaviour is not None:
        return _behaviour_references(behaviour, skill_sets, open_width, duration, poses)
    if any(len(skills) != 1 for skills in skill_sets):
        raise ConfigError(f"several skills ({', '.join(next(skills for skills in skill_sets if len(skills) != 1))}) but no behaviour to sequence them")
    return _model_references([next(iter(skills.values())) for skills in skill_sets], [duration] * len(skill_sets), poses=poses)


def _behaviour_references(
    behaviour: Behaviour, models: Sequence[dict[str, HSMM]], open_width: float, duration: float | None = None, poses: Mapping[str, Pose] | None = None
) -> list[Reference]:
    """The behaviour's reference for each of N sets of its skills (the same skills with other
    parameters), each skill step retrieved for all of them together."""
    poses = poses or {}
    retrieved = [
        _model_references(
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
            if pieces:
                before = turns[-1][-1] if turns[-1] is not None else DOWN
                positions, turn = eased_in(positions, turn, pieces[-1][-1], before)
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
    positions, names, followed = np.concatenate(pieces), np.concatenate(skills), np.concatenate(states)
    gripper = closing_ramps(np.concatenate(grippers), GRIPPER_SPEED * TIME_STEP)
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


def eased_in(positions: np.ndarray, orientations: np.ndarray | None, position: np.ndarray, orientation: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """A skill's `T x 3` positions and `T x 4` orientations (None: straight down) moved to start
    at `position` (`3`) and `orientation` (`4`), the offset fading out over its first
    `EASE_SECONDS` along a quintic whose speed and acceleration are zero at both ends, so that
    the joined reference stays continuous in position, velocity and acceleration; orientations
    None while both are straight down."""
    count = min(len(positions), _steps(EASE_SECONDS) + 1)
    progress = np.linspace(0.0, 1.0, count)
    fading = np.zeros(len(positions))
    fading[:count] = 1 - progress**3 * (10 - 15 * progress + 6 * progress**2)
    moved = positions + fading[:, None] * (np.asarray(position) - positions[0])
    turns = orientations if orientations is not None else np.tile(DOWN, (len(positions), 1))
    turn = rotations.to_rotvec(rotations.multiply(orientation, rotations.conjugate(turns[0])))
    if orientations is None and not np.any(turn):
        return moved, None
    return moved, rotations.multiply(rotations.from_rotvec(fading[:, None] * turn), turns)


def closing_ramps(openings: np.ndarray, step: float) -> np.ndarray:
    """Piecewise-constant `T` openings, each closing followed at most `step` per sample (a ramp
    from where the opening had got to); an opening follows at once."""
    followed = openings.astype(float)
    changes = np.flatnonzero(openings[1:] < openings[:-1]) + 1
    for index, change in enumerate(changes):
        end = changes[index + 1] if index + 1 < len(changes) else len(openings)
        ramp = np.maximum(followed[change - 1] - step * np.arange(1, end - change + 1), openings[change])
        followed[change:end] = np.maximum(ramp, openings[change:end])  # an opening on the way ends the ramp
    return followed


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
    return [reference.positions[:1] for reference in _model_references(firsts, [2 * first.sample_period_ for first in firsts], step.name, step.poses(poses))]


def _model_references(
    models: Sequence[HSMM], durations: Sequence[float | None], name: str = "skill", poses: Mapping[str, Pose] | None = None
) -> list[Reference]:
    """The reference of each of N models of the skill `name` (for `durations` seconds each, None:
    its expected duration), retrieved together (`retrieve_batch`): its trajectory at the
    simulation rate, its samples labelled with `name` and the (1-based) HSMM state they follow;
    a TP-HSMM retrieved for its frames at `poses` (frame name -> pose)."""
    for model in models:
        missing = [signal for signal in POSITION_SIGNALS if signal not in model.signal_names_]
        if missing:
            raise ModelError(f"the model has no signal {', '.join(missing)}: only position skills (x, y, z) can be executed")
    frames = {frame: pose for model in models for frame, pose in _skill_poses(model, poses or {}, name).items()}
    trajectories = retrieve_batch(models, durations, rate=SIMULATION_RATE, poses=frames)
    return [_reference(model, trajectory, name) for model, trajectory in zip(models, trajectories)]


def _reference(model: HSMM, trajectory: Trajectory, name: str) -> Reference:
    """The reference of a retrieved `trajectory` of `model`, its samples labelled `name`."""
    columns = [model.signal_names_.index(signal) for signal in POSITION_SIGNALS]
    gripper = trajectory.positions[:, model.signal_names_.index("gripper")] if "gripper" in model.signal_names_ else None
    skills = np.full(trajectory.times.shape, name)
    return Reference(
        trajectory.times, trajectory.positions[:, columns], gripper, skills=skills, states=trajectory.states + 1, orientations=trajectory.orientations
    )


def _skill_poses(model: HSMM, poses: Mapping[str, Pose], name: str = "skill") -> dict[str, Pose]:
    """The poses of the frames of `model` (none for a plain HSMM), from `poses`; ConfigError
    naming the frames the scene lacks."""
    if not isinstance(model, TPHSMM):
        return {}
    missing = [frame for frame in model.frame_names_ if frame != BASE_FRAME and frame not in poses]
    if missing:
        known = ", ".join(poses) or "none"
        raise ConfigError(f"the {name} model is learned in frame {', '.join(missing)}, which the scene does not have (its frames: {known})")
    return {frame: poses[frame] for frame in model.frame_names_ if frame != BASE_FRAME}
