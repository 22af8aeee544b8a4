"""The trial loop on a cheap synthetic objective (no simulation)."""

import numpy as np
import pytest

from stl_lfd.optim.loop import run_remaining_trials, search_method
from stl_lfd.optim.methods.base import Problem, sobol_points
from stl_lfd.optim.methods.stl import CompositeSearch
from stl_lfd.optim.settings import Optimizer
from stl_lfd.optim.trials import Outcome, Trial, best_trial

BOUNDS = np.array([[0.0, -1.0, 2.0], [1.0, 1.0, 4.0]])
TARGET = np.array([0.7, 0.2, 3.1])


def objective(x):
    return Outcome(0.3 - float(np.linalg.norm((x - TARGET) / (BOUNDS[1] - BOUNDS[0]))))


def run(optimizer, history=(), function=objective):
    return run_remaining_trials(function, search_method(optimizer, Problem(BOUNDS)), list(history), lambda trial, payload: None)


def points(history):
    return np.array([trial.x for trial in history])


@pytest.mark.slow
def test_the_same_seed_gives_the_same_trials():
    optimizer = Optimizer("pi", initial=4, trials=8, seed=3)
    first, second = run(optimizer), run(optimizer)
    assert np.array_equal(points(first), points(second))
    other = run(Optimizer("pi", initial=4, trials=8, seed=4))
    assert not np.allclose(points(first)[:4], points(other)[:4])


@pytest.mark.slow
def test_resuming_from_a_recorded_history_continues_exactly():
    optimizer = Optimizer("pi", initial=4, trials=9, seed=1)
    uninterrupted = run(optimizer)
    partial = run(Optimizer("pi", initial=4, trials=6, seed=1))
    resumed = run(optimizer, partial)
    assert [trial.phase for trial in resumed] == ["sobol"] * 4 + ["pi"] * 5
    assert np.array_equal(points(resumed), points(uninterrupted))


@pytest.mark.slow
@pytest.mark.parametrize("method", ["pi", "logei", "random"])
def test_every_method_stays_inside_the_bounds_and_shares_the_initial_design(method):
    history = run(Optimizer(method, initial=3, trials=7, seed=0))
    x = points(history)
    assert np.all((x >= BOUNDS[0]) & (x <= BOUNDS[1]))
    assert np.array_equal(x[:3], points(run(Optimizer("random", initial=3, trials=3, seed=0))))
    assert [trial.phase for trial in history][3:] == [method] * 4


@pytest.mark.slow
def test_the_acquisition_improves_on_the_initial_design():
    history = run(Optimizer("pi", initial=5, trials=20, seed=0))
    best_initial = max(trial.robustness for trial in history[:5])
    assert best_trial(history).robustness > best_initial
    assert best_trial(history).robustness > 0.2


@pytest.mark.slow
def test_a_failing_trial_is_recorded_and_the_loop_goes_on():
    calls = []

    def flaky(x):
        calls.append(x)
        if len(calls) == 2:
            raise RuntimeError("simulation exploded")
        if len(calls) == 6:
            return Outcome(float("nan"))
        return objective(x)

    history = run(Optimizer("pi", initial=3, trials=8, seed=0), function=flaky)
    assert len(history) == 8
    assert history[1].status == "failed" and "simulation exploded" in history[1].error
    assert history[5].status == "failed" and "nan" in history[5].error
    assert history[1].robustness is None and not history[1].satisfied
    assert all(trial.status == "ok" for index, trial in enumerate(history) if index not in (1, 5))


def hopeless(x):  # violated everywhere, with gains far below the distance to satisfaction
    return Outcome(-1.0 - 1e-3 * float(x[0]))


def stalls(*trials: tuple[str, float]) -> bool:
    """`stalled` on a history of (phase, robustness) trials."""
    history = [Trial(number, phase, np.zeros(3), value) for number, (phase, value) in enumerate(trials, start=1)]
    return CompositeSearch(Problem(BOUNDS), Optimizer("stl")).stalled(history, np.array([value for _, value in trials]))


def test_stl_explores_with_the_sobol_sequence_while_it_stalls_on_a_violated_spec():
    history = run(Optimizer("stl", initial=3, trials=9, seed=2), function=hopeless)
    assert [trial.phase for trial in history] == ["sobol"] * 3 + ["stl", "stl", "explore"] * 2
    sobol = sobol_points(BOUNDS, 9, 2)
    assert np.array_equal(points(history)[[5, 8]], sobol[[5, 8]])  # the design's own continuation


def test_stl_does_not_explore_once_the_spec_is_satisfied_or_while_the_model_gains():
    history = run(Optimizer("stl", initial=3, trials=6, seed=2), function=lambda x: Outcome(1.0 - 1e-3 * float(x[0])))
    assert [trial.phase for trial in history][3:] == ["stl"] * 3
    design = [("sobol", -1.0), ("sobol", -0.8)]
    assert stalls(*design, ("stl", -0.78), ("stl", -0.75))  # gains of 2.5 % and 4 % of the distance
    assert not stalls(*design, ("stl", -0.78))  # one stalled trial is not a stall
    assert not stalls(*design, ("stl", -0.78), ("stl", -0.7))  # gained 10.3 %
    assert not stalls(*design, ("stl", -0.78), ("explore", -0.9))
    assert not stalls(*design, ("stl", -0.78), ("stl", 0.1))


def test_a_stalled_batch_of_parallel_trials_starts_with_the_exploring_trial():
    history = run(Optimizer("stl", initial=2, trials=12, seed=1, workers=2), function=hopeless)
    phases = [trial.phase for trial in history]
    assert phases[:2] == ["sobol"] * 2 and "explore" in phases
    for number, phase in enumerate(phases):
        if phase == "explore":
            assert (number - 2) % 2 == 0  # first in its batch
            assert np.array_equal(history[number].x, sobol_points(BOUNDS, number + 1, 1)[number])
