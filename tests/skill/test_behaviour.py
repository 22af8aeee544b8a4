"""Behaviour files and the joined reference of a behaviour."""

import copy
from pathlib import Path

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.errors import ConfigError
from stl_lfd.optim import load_task
from stl_lfd.sim import TIME_STEP, Reference
from stl_lfd.skill.behaviour import ActionStep, load_behaviour
from stl_lfd.skill.reference import EASE_SECONDS, GRIPPER_SPEED, build_reference, closing_ramps, eased_in
from tests.conftest import ROOT

BEHAVIOUR = ROOT / "configs" / "behaviours" / "pick_insert.yaml"


def test_the_bundled_behaviour_reads():
    behaviour = load_behaviour(BEHAVIOUR)
    assert behaviour.scene == "pick_insert"
    assert [step.name for step in behaviour.skills] == ["pick", "insert"]
    assert [step.action for step in behaviour.steps if isinstance(step, ActionStep)] == ["grasp", "release"]


def test_the_reference_joins_skills_and_actions(learned_model):
    behaviour = load_behaviour(BEHAVIOUR)
    models = {"pick": learned_model, "insert": learned_model}
    reference = build_reference(models, behaviour, open_width=0.08)
    (grasp_time, grasp), (release_time, release) = reference.events
    assert (grasp, release) == ("grasp", "release")
    first_skill = learned_model.expected_duration() + 1.0
    assert grasp_time == pytest.approx(first_skill, abs=2 * TIME_STEP)
    closing = (reference.times >= grasp_time) & (reference.times < release_time)
    closed = closing & (reference.times >= grasp_time + 0.08 / GRIPPER_SPEED + TIME_STEP)
    assert np.all(reference.gripper[closed] == 0.0) and np.all(reference.gripper[reference.times < grasp_time] == 0.08)
    assert np.all(np.diff(reference.gripper[closing]) <= 0) and np.all(reference.gripper[closing] < 0.08)
    assert -np.diff(reference.gripper).min() == pytest.approx(GRIPPER_SPEED * TIME_STEP)  # the fingers close at GRIPPER_SPEED
    assert np.all(reference.gripper[reference.times >= release_time] == 0.08)  # and open at once
    hold = (reference.times >= grasp_time) & (reference.times < grasp_time + 1.0)
    assert np.ptp(reference.positions[hold], axis=0).max() == 0.0  # the hand holds still while grasping
    padded = build_reference(models, behaviour, 0.08, duration=reference.duration + 5)
    assert padded.duration == pytest.approx(reference.duration + 5, abs=TIME_STEP)
    assert np.all(padded.positions[-1] == reference.positions[-1])


def test_each_skill_starts_where_the_step_before_left_the_hand(learned_model):
    # The same model for both skills: the second's first state is far from where the first ends.
    behaviour = load_behaviour(BEHAVIOUR)
    models = {"pick": learned_model, "insert": learned_model}
    reference = build_reference(models, behaviour, open_width=0.08)
    assert np.linalg.norm(learned_model.means_[0, :3] - reference.positions[reference.skills == "pick"][-1]) > 0.05
    speeds = np.linalg.norm(np.diff(reference.positions, axis=0), axis=1) / TIME_STEP
    assert speeds.max() < 1.0  # m/s: no jump anywhere (a jump of 5 cm would be 12 m/s), joins included
    accelerations = np.linalg.norm(np.diff(reference.positions, 2, axis=0), axis=1) / TIME_STEP**2
    assert accelerations.max() < 5.0  # m/s^2: each skill starts at rest


def write(tmp_path: Path, text: str) -> Path:
    (tmp_path / "demos").mkdir(exist_ok=True)
    path = tmp_path / "behaviour.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "text, message",
    [
        ("scene: s\nsteps:\n  - {skill: a, demos: demos, colour: red}\n", r"unknown key 'steps\[0\].colour'"),
        ("scene: s\nsteps:\n  - {action: wave}\n", r"'steps\[0\].action' must be one of grasp, release"),
        ("scene: s\nsteps:\n  - {skill: a, demos: nowhere}\n", r"'steps\[0\].demos' names nowhere, which does not exist"),
        ("scene: s\nsteps:\n  - {skill: a}\n", r"'steps\[0\]' needs exactly one of 'demos'"),
        ("scene: s\nsteps:\n  - {skill: a, demos: demos}\n  - {skill: a, demos: demos}\n", "skill names must be unique"),
        ("scene: s\nsteps:\n  - {action: grasp}\n", "'steps' has no skill"),
        ("scene: s\nsteps: []\n", "'steps' must be a non-empty list"),
        ("steps:\n  - {skill: a, demos: demos}\n", "missing key 'scene'"),
        ("scene: s\nsteps:\n  - {skill: a, demos: demos, learn_in: holder}\n", r"'steps\[0\].learn_in' must list the frames"),
        ("scene: s\nsteps:\n  - {skill: a, demos: demos, min_spread: 5mm}\n", r"'steps\[0\].min_spread' 5mm: give auto, none, or a position"),
    ],
)
def test_bad_behaviour_files_name_the_file_and_the_step(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=message) as error:
        load_behaviour(path)
    assert str(path) in str(error.value)


def test_task_parameters_must_name_skills_of_the_behaviour(tmp_path):
    path = tmp_path / "task.yaml"
    path.write_text(f"spec: {ROOT / 'specs' / 'phi3.stl'}\nbehaviour: {BEHAVIOUR}\nduration: 48\nparameters:\n  place:\n    durations: {{components: all}}\n")
    with pytest.raises(ConfigError, match="unknown key 'parameters.place' \\(known: pick, insert\\)"):
        load_task(path)


@pytest.fixture(scope="module")
def pick_insert_models():
    from stl_lfd.skill.behaviour import behaviour_models

    return behaviour_models(load_behaviour(BEHAVIOUR))


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_the_unoptimised_behaviour_picks_then_pushes_the_shaft_onto_the_holder(pick_insert_models, engine):
    import warnings

    from stl_lfd.sim import TrackingWarning, execute, load_scene

    behaviour, scene = load_behaviour(BEHAVIOUR), load_scene("pick_insert")
    reference = build_reference(pick_insert_models, behaviour, scene.gripper_opening, 48, scene.frame_poses)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        signals = execute(reference, scene, engine).signals  # (that it repeats exactly: tests/sim/test_mujoco.py)
    force, times = signals.columns["force"], signals.times
    grasp_time = reference.events[0][0]
    assert force[times < grasp_time - 0.5].max() < 1.0  # reaching for the shaft touches nothing
    assert 5.0 < force.max() < 60.0  # the shifted insertion hits the holder's edge, as a compliant arm does


def test_a_skill_from_one_demonstration_learned_in_its_object_frame(tmp_path):
    from stl_lfd.hsmm import TPHSMM
    from stl_lfd.skill.behaviour import behaviour_models

    behaviour = load_behaviour(ROOT / "configs" / "behaviours" / "pick_reorient_insert_one.yaml")
    assert [step.learn_in for step in behaviour.skills] == [("shaft",), ("holder",)]
    models = behaviour_models(behaviour)
    assert isinstance(models["insert"], TPHSMM) and models["insert"].frame_names_ == ["holder"]
    assert models["insert"].min_spread is not None  # one demonstration: widened
    narrower = load_behaviour(
        write(tmp_path, f"scene: s\nsteps:\n  - {{skill: a, demos: {ROOT / 'demos' / 'pick_lying' / 'demo_01.csv'}, min_spread: [2mm, 1deg, 5%]}}\n")
    )
    assert behaviour_models(narrower)["a"].min_spread.position == pytest.approx(0.002)


def test_a_batch_of_behaviour_references_is_each_reference_alone(pick_insert_models):
    """Method `plan` retrieves the references of many candidate points together: exactly the
    reference of each alone (its trial on the kinematic backend executes it)."""
    from stl_lfd.sim import load_scene
    from stl_lfd.skill.reference import build_references

    behaviour, scene = load_behaviour(BEHAVIOUR), load_scene("pick_insert")
    rng = np.random.default_rng(0)
    sets = []
    for _ in range(3):
        skills = {name: copy.deepcopy(model) for name, model in pick_insert_models.items()}
        skills["pick"].duration_means_ = skills["pick"].duration_means_ * rng.uniform(0.8, 1.2, size=skills["pick"].n_states)
        skills["insert"].means_ = skills["insert"].means_ + rng.normal(scale=0.005, size=skills["insert"].means_.shape)
        sets.append(skills)
    batch = build_references(sets, behaviour, scene.gripper_opening, 48, scene.frame_poses)
    for skills, reference in zip(sets, batch):
        alone = build_reference(skills, behaviour, scene.gripper_opening, 48, scene.frame_poses)
        assert reference.events == alone.events
        for name in ("times", "positions", "gripper", "skills", "states"):
            assert np.array_equal(getattr(reference, name), getattr(alone, name)), name
        assert (reference.orientations is None and alone.orientations is None) or np.array_equal(reference.orientations, alone.orientations)


def test_eased_in_starts_where_asked_and_ends_as_retrieved():
    times = np.arange(0, 3, TIME_STEP)
    positions = np.column_stack([0.1 * times, np.zeros_like(times), np.full_like(times, 0.3)])
    turned = rotations.multiply(rotations.from_rotvec(np.array([0.0, 0.0, 0.2])), rotations.DOWN)
    moved, orientations = eased_in(positions, None, np.array([0.0, 0.02, 0.3]), turned)
    assert np.allclose(moved[0], [0.0, 0.02, 0.3]) and np.allclose(orientations[0], turned)
    later = times > EASE_SECONDS
    assert np.allclose(moved[later], positions[later]) and np.allclose(orientations[later], rotations.DOWN)
    assert np.allclose(moved[1] - moved[0], positions[1] - positions[0], atol=1e-7)  # it leaves at the skill's own speed
    same, none = eased_in(positions, None, positions[0], rotations.DOWN)
    assert none is None and np.array_equal(same, positions)


def test_closings_ramp_and_openings_follow_at_once():
    openings = np.array([0.08] * 3 + [0.0] * 3 + [0.08] * 2 + [0.04] * 2)
    assert np.allclose(closing_ramps(openings, 0.03), [0.08, 0.08, 0.08, 0.05, 0.02, 0.0, 0.08, 0.08, 0.05, 0.04])
    short = np.array([0.08, 0.0, 0.08, 0.08])
    assert np.allclose(closing_ramps(short, 0.03), [0.08, 0.05, 0.08, 0.08])  # opened again before it had closed


def test_an_action_ends_where_the_next_skill_starts():
    times = np.arange(6) * 0.5
    skills = np.array(["pick", "pick", "grasp", "grasp", "carry", "carry"])
    reference = Reference(times, np.zeros((6, 3)), events=((1.0, "grasp"),), skills=skills)
    assert reference.action_end(1.0) == 2.0
    assert Reference(times, np.zeros((6, 3)), events=((1.0, "grasp"),)).action_end(1.0) == 1.0
