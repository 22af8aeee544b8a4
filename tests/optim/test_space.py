import numpy as np
import pytest

from stl_lfd.optim import build_space
from stl_lfd.optim.settings import DurationParameters, MeanParameters, Parameters
from stl_lfd.optim.space import transition_entries


def test_bounds_follow_the_state_and_duration_spreads(learned_model):
    parameters = Parameters(MeanParameters((2, 3), ("x", "y", "z"), beta=2.0), DurationParameters("all", 1.0))
    space = build_space(learned_model, parameters)
    stds = np.sqrt(np.diag(learned_model.covars_[1]))
    assert space.names[:3] == ("mean[2].x", "mean[2].y", "mean[2].z")
    assert np.allclose(space.upper[:3] - space.initial[:3], 2.0 * stds)
    assert np.allclose(space.initial[:3], learned_model.means_[1])
    durations = slice(6, 12)
    assert np.allclose(space.initial[durations], learned_model.duration_means_)
    assert np.allclose(space.upper[durations] - space.initial[durations], learned_model.duration_stds_)
    assert np.all(space.lower[durations] >= learned_model.sample_period_)
    assert np.all((space.lower <= space.initial) & (space.initial <= space.upper))


def test_the_reduced_band_has_successors_one_and_two_ahead():
    assert transition_entries(6, "band") == [(0, 1), (0, 2), (1, 2), (1, 3), (2, 3), (2, 4), (3, 4), (3, 5), (4, 5)]
    assert len(transition_entries(6, "full")) == 30
    assert transition_entries(6, "none") == []


def test_apply_sets_the_values_clips_to_bounds_and_renormalises_rows(learned_model):
    space = build_space(learned_model, Parameters(MeanParameters((3,), ("x",)), DurationParameters((4,)), "band"))
    x = space.initial.copy()
    x[0] = space.upper[0] + 1.0  # outside: clipped
    x[1] = space.initial[1] + 0.5 * (space.upper[1] - space.initial[1])
    x[2:] = 0.5  # every band entry
    adapted = space.apply(learned_model, x)
    assert adapted.means_[2, 0] == pytest.approx(space.upper[0])
    assert adapted.duration_means_[3] == pytest.approx(x[1])
    rows = adapted.transmat_.sum(axis=1)
    assert np.allclose(rows[:5], 1.0) and rows[5] == 0.0  # the last state still absorbs
    assert np.allclose(adapted.transmat_[0, 1:3], 0.5)
    assert learned_model.means_[2, 0] == pytest.approx(space.initial[0])  # the original is untouched


def test_the_initial_point_reproduces_the_model(learned_model):
    space = build_space(learned_model, Parameters(MeanParameters((2, 3)), DurationParameters("all"), "band"))
    adapted = space.apply(learned_model, space.initial)
    assert np.allclose(adapted.means_, learned_model.means_)
    assert np.allclose(adapted.duration_means_, learned_model.duration_means_)
    assert np.allclose(adapted.normalized_transmat(), learned_model.normalized_transmat())
