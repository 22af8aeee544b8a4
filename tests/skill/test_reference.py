"""The one reference builder: a single skill or a behaviour's skills, one set of parameters or
many at once, each the same reference whichever way it was asked for."""

import copy

import numpy as np
import pytest

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.sim import SIMULATION_RATE, load_scene
from stl_lfd.skill import PlacedSkill, build_reference, build_references, load_behaviour
from tests.conftest import ROOT


def same(first, second) -> bool:
    """Two references equal sample for sample, labels and events included."""
    arrays = ("times", "positions", "gripper", "skills", "states")
    return all(np.array_equal(getattr(first, name), getattr(second, name)) for name in arrays) and first.events == second.events


def test_a_single_skill_is_its_retrieved_trajectory_labelled_with_its_states(learned_model):
    reference = build_reference({"skill": learned_model}, duration=20.0)
    assert reference.times[1] - reference.times[0] == pytest.approx(1 / SIMULATION_RATE)
    assert reference.duration == pytest.approx(20.0, abs=1 / SIMULATION_RATE)
    assert set(reference.skills) == {"skill"} and reference.states.min() == 1 and reference.states.max() <= learned_model.n_states
    assert reference.events == () and reference.orientations is None


def test_many_sets_at_once_are_each_the_reference_of_that_set_alone(learned_model):
    changed = copy.deepcopy(learned_model)
    changed.means_[2, 0] += 0.02
    changed.duration_means_[1] *= 1.2
    sets = [{"skill": learned_model}, {"skill": changed}]
    batch = build_references(sets, duration=22.0)
    assert all(same(together, build_reference(skills, duration=22.0)) for together, skills in zip(batch, sets))
    assert not np.array_equal(batch[0].positions, batch[1].positions)


def test_a_behaviour_through_a_placed_scene_is_the_same_reference(learned_model):
    behaviour = load_behaviour(ROOT / "configs" / "behaviours" / "pick_insert.yaml")
    scene = load_scene(behaviour.scene)
    models = {"pick": learned_model, "insert": learned_model}
    placed = PlacedSkill(models, behaviour, scene, duration=48.0)
    direct = build_reference(models, behaviour, scene.gripper_opening, 48.0, scene.frame_poses)
    assert same(placed.reference(), direct) and same(placed.references([models])[0], direct)
    assert [action for _, action in direct.events] == ["grasp", "release"]


def test_what_cannot_be_built_is_said(learned_model):
    with pytest.raises(ConfigError, match="several skills .* but no behaviour to sequence them"):
        build_reference({"pick": learned_model, "insert": learned_model})
    no_position = copy.deepcopy(learned_model)
    no_position.signal_names_ = ["a", "b", "c"]
    with pytest.raises(ModelError, match="the model has no signal x, y, z"):
        build_reference({"skill": no_position})
