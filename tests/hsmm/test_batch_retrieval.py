"""Batched retrieval (method `plan` retrieves the plans of many candidate points at once): a
batch gives exactly what each of its members gives alone.

Exactly, not nearly: on the kinematic backend a trial executes its plan, and method `plan`
learns the execution's difference from the plan, which must then be 0, not rounding noise.
"""

import copy

import numpy as np
import pytest

from stl_lfd.hsmm import lqt
from stl_lfd.hsmm.retrieval import retrieve, retrieve_batch


def tracking_problem(rng: np.random.Generator, steps: int, segments: int) -> lqt.Tracking:
    """A random tracking problem of a 2-D double integrator: `segments` states over `steps` steps."""
    Q = np.zeros((segments, 4, 4))
    for k in range(segments):
        L = rng.normal(size=(2, 2))
        Q[k, :2, :2] = L @ L.T + np.eye(2)
    targets = np.zeros((segments, 4))
    targets[:, :2] = rng.normal(size=(segments, 2))
    ids = np.sort(rng.integers(0, segments, size=steps))
    return lqt.Tracking(Q, 0.01 * np.eye(2), targets, rng.normal(size=4), ids)


def test_a_batch_of_tracking_problems_is_each_problem_solved_alone():
    rng = np.random.default_rng(0)
    A, B = lqt.double_integrator(2, 0.1)
    problems = [tracking_problem(rng, steps, segments) for steps, segments in ((40, 3), (400, 4), (2, 1), (400, 4), (151, 6))]
    batch = lqt.solve_batch(A, B, problems)
    for problem, states in zip(problems, batch):
        alone, controls = lqt.solve(A, B, problem.Q, problem.R, problem.targets, problem.x0, problem.segment_ids)
        assert np.array_equal(states, alone)
        assert states.shape == (problem.segment_ids.size, 4) and np.array_equal(states[0], problem.x0)
        np.testing.assert_allclose(alone[1:], alone[:-1] @ A.T + controls @ B.T, atol=1e-12)  # the controls drive the states


def adapted(model, rng: np.random.Generator, count: int) -> list:
    """`count` copies of `model` with other means of states 2-3 and other durations, as the
    optimiser's candidate points make them."""
    models = []
    for _ in range(count):
        other = copy.deepcopy(model)
        other.means_[1:3] += rng.normal(scale=0.01, size=(2, other.n_features))
        other.duration_means_ = other.duration_means_ * rng.uniform(0.8, 1.2, size=other.n_states)
        models.append(other)
    return models


@pytest.mark.parametrize("duration", [22.0, None])  # None: each model's expected duration, lengths differ
def test_a_batch_of_retrievals_is_each_retrieval_alone(learned_model, duration):
    models = adapted(learned_model, np.random.default_rng(1), 6)
    batch = retrieve_batch(models, [duration] * len(models), rate=240)
    assert duration is not None or len({len(trajectory.times) for trajectory in batch}) > 1
    for model, trajectory in zip(models, batch):
        alone = retrieve(model, duration, rate=240)
        for name in ("times", "positions", "velocities", "states"):
            assert np.array_equal(getattr(trajectory, name), getattr(alone, name)), name
