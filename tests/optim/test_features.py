"""What method `stl`'s GP sees: the state path a point selects, the means on it and when each
of its states starts."""

import copy
import warnings

import numpy as np
import pytest
import torch

from stl_lfd.optim import SearchSpace, build_space
from stl_lfd.optim.features import SKIPPED, path_features
from stl_lfd.optim.methods.gp import fit_multi_output_gp
from stl_lfd.optim.methods.posterior import PartsPosterior
from stl_lfd.optim.settings import DurationParameters, MeanParameters, Parameters

BAND = Parameters(MeanParameters((2, 3), ("x", "y", "z")), DurationParameters("all", 1.0), "band")


def two_skills(model):
    """A behaviour-like space: a skill with the band, then one with means only."""
    models = {"first": model, "second": copy.deepcopy(model)}
    space = SearchSpace({"first": build_space(model, BAND), "second": build_space(model, Parameters(MeanParameters((6,), ("x", "y"))))})
    return models, space


def unit_points(space, count, seed):
    return np.random.default_rng(seed).random((count, space.dimension))


def test_paths_are_those_the_adapted_models_follow(learned_model):
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    unit = unit_points(space, 200, 0)
    unit[:20, 6 + 6 : 6 + 6 + 9] = 0.5  # every band entry equal: ties go to the lower state
    unit[20:40, 6 + 6 : 6 + 6 + 9] = np.round(unit[20:40, 6 + 6 : 6 + 6 + 9])  # rows of zeros and ones
    points = space.bounds[0] + unit * (space.bounds[1] - space.bounds[0])
    visited = features.skills[0].visited(points)
    expected = np.zeros_like(visited)
    paths = set()
    for row, point in enumerate(points):
        path = space.apply(models, point)["first"].nominal_path()
        expected[row, path] = True
        paths.add(tuple(path))
    np.testing.assert_array_equal(visited, expected)
    assert len(paths) > 4  # the sample covers several paths


def test_times_are_when_the_adapted_models_states_start(learned_model):
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    skill = features.skills[0]
    points = space.bounds[0] + unit_points(space, 50, 3) * (space.bounds[1] - space.bounds[0])
    positions = skill.positions(points)
    times = skill.times(torch.as_tensor(points), positions).numpy()
    for row, point in enumerate(points):
        model = space.apply(models, point)["first"]
        path = model.nominal_path()
        starts = np.concatenate([[0.0], np.cumsum(model.duration_means_[path])[:-1]])
        np.testing.assert_allclose(times[row, path], starts, atol=1e-9)
        assert times[row, -1] == pytest.approx(model.expected_duration())


def test_points_that_execute_alike_look_alike(learned_model):
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    assert features.dimension == 6 + 6 + 6 + 2  # means, five starts and the end, six indicators, the second skill
    unit = torch.as_tensor(unit_points(space, 1, 1))
    unit[0, 12:21] = torch.tensor([1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0])  # 1 -> 2 -> 4 -> 5 -> 6: state 3 skipped
    other = unit.clone()
    other[0, 3:6] = 0.1  # the mean of state 3
    other[0, 6 + 2] = 0.9  # the duration of state 3: it starts no later state
    other[0, 12:21] = torch.tensor([0.9, 0.2, 0.3, 0.8, 0.6, 0.1, 0.7, 0.2, 0.6])  # the same successors
    seen, other_seen = features(unit), features(other)
    torch.testing.assert_close(seen, other_seen)
    assert seen[0, 12:18].tolist() == [1.0, 1.0, 0.0, 1.0, 1.0, 1.0]
    assert torch.all(seen[0, 3:6] == SKIPPED) and seen[0, 6 + 1] == SKIPPED  # state 3's start
    torch.testing.assert_close(seen[0, -2:], unit[0, -2:])  # no transitions: passed through


def test_features_are_differentiable_in_the_parameters_on_the_path(learned_model):
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    unit = torch.as_tensor(unit_points(space, 3, 2)).requires_grad_(True)
    features(unit).sum().backward()
    assert torch.all(unit.grad[:, 12:21] == 0)  # the path is a step function of the entries
    assert torch.all(unit.grad[:, -2:] == 1)
    assert torch.all(unit.grad[:, :12] >= 0) and torch.any(unit.grad[:, :12] == 1)


def test_spaces_of_means_alone_have_no_features(learned_model):
    space = SearchSpace({"skill": build_space(learned_model, Parameters(MeanParameters((2,), ("x",))))})
    assert path_features(space, {"skill": learned_model}) is None


def test_durations_alone_are_seen_as_times_along_the_fixed_path(learned_model):
    space = SearchSpace({"skill": build_space(learned_model, Parameters(MeanParameters((2,), ("x",)), DurationParameters("all", 1.0)))})
    features = path_features(space, {"skill": learned_model})
    assert features.dimension == 1 + 6  # the mean, five starts and the end
    unit = torch.tensor([[0.3] + [0.0] * 6, [0.3] + [1.0] * 6, [0.3, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
    seen = features(unit)
    assert torch.all(seen[:, 0] == 0.3)
    torch.testing.assert_close(seen[0, 1:], torch.zeros(6, dtype=torch.float64))  # every time at its least
    torch.testing.assert_close(seen[1, 1:], torch.ones(6, dtype=torch.float64))  # and at its largest
    assert seen[2, 1] == 1  # only the first state at its longest: the second starts as late as it can
    assert torch.all(seen[2, 2:] > 0) and torch.all(seen[2, 2:] < 1)  # and every later time is later


def test_a_gp_on_features_predicts_the_path_that_satisfies(learned_model):
    """A part that holds only when state 3 is skipped: from 12 trials, the GP on features
    predicts its sign at new points almost everywhere; on the raw entries the step lies along
    two of nine coordinates, and the GP guesses far more often wrong."""
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    bounds = space.bounds

    def part_values(unit):
        points = bounds[0] + unit * (bounds[1] - bounds[0])
        return np.where(features.skills[0].visited(points)[:, 2], -0.1, 0.1) - 0.05 * np.abs(unit[:, -1] - 0.5)

    correct = {}
    for name, encode in (("features", features), ("raw", lambda points: points)):
        hits = 0
        for seed in range(3):
            trials, new = unit_points(space, 12, 20 + seed), torch.as_tensor(unit_points(space, 100, 30 + seed))
            model = fit_multi_output_gp(encode(torch.as_tensor(trials)).numpy(), part_values(trials)[:, None])
            mean, _ = PartsPosterior(model)(encode(new))
            hits += int(np.sum(np.sign(mean[:, 0].numpy()) == np.sign(part_values(new.numpy()))))
        correct[name] = hits / 300
    assert correct["features"] > 0.95
    assert correct["raw"] < correct["features"] - 0.1


def test_a_state_on_no_sampled_path_has_no_time(learned_model):
    models, space = two_skills(learned_model)
    features = path_features(space, models)
    unit = torch.as_tensor(unit_points(space, 64, 4))
    unit[:, 12:21] = torch.tensor([1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0])  # every path skips state 3
    points = torch.as_tensor(space.bounds[0]) + unit * torch.as_tensor(space.bounds[1] - space.bounds[0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scale = features._time_scale(features.skills[0], points)
    assert 2 not in scale.columns and list(scale.columns) == [1, 3, 4, 5, 6]  # state 3's start; the end is 6
    assert np.all(scale.high > scale.low)
