"""Optimising a skill's orientation: `rx, ry, rz` among a state's coordinates move its mean
orientation, bounded by its orientation covariance (`configs/turn.yaml`)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from stl_lfd import rotations
from stl_lfd.errors import ConfigError
from stl_lfd.hsmm import learn_from_folder, retrieve
from stl_lfd.optim import build_space, finish_run, load_task, start_run
from stl_lfd.optim.settings import MeanParameters, Parameters
from tests.conftest import ROOT


@pytest.fixture(scope="module")
def turn_skill():
    return learn_from_folder(ROOT / "demos" / "turn", 5)[0]


def test_orientation_parameters_are_bounded_by_the_states_orientation_covariance(turn_skill):
    space = build_space(turn_skill, Parameters(means=MeanParameters(components=(5,), coordinates=("rx", "ry", "rz"), beta=2.0)))
    assert space.names == ("orient[5].rx", "orient[5].ry", "orient[5].rz")
    stds = np.sqrt(np.diag(turn_skill.covars_[4])[3:6])
    assert np.allclose(space.upper - space.initial, 2.0 * stds) and np.allclose(space.initial, turn_skill.means_[4, 3:6])
    turned = space.apply(turn_skill, space.upper)
    end = retrieve(turned).orientations[-1]
    assert np.linalg.norm(rotations.log_map(turned.orientations(turned.means_[4]), end)) < np.radians(2)  # the retrieval follows the moved mean


def test_a_position_skill_has_no_orientation_to_move(learned_model):
    with pytest.raises(ConfigError, match="the model has no signal rx"):
        build_space(learned_model, Parameters(means=MeanParameters(components=(2,), coordinates=("rx",))))


@pytest.mark.slow
def test_the_turn_task_is_satisfied_by_moving_the_last_states_orientation(tmp_path):
    task = load_task(ROOT / "configs" / "turn.yaml")
    with start_run(task, tmp_path / "run") as prepared:
        summary = finish_run(prepared)
    assert prepared.summary.initial_robustness < 0 < summary.best_robustness
    best = json.loads((tmp_path / "run" / "summary.json").read_text())["best_parameters"]
    assert set(best) == {f"orient[{state}].{axis}" for state in (4, 5) for axis in ("rx", "ry", "rz")}
