"""Method `plan`: the plan as the prior, the difference learned from the trials."""

import json

import numpy as np
import pytest

from stl_lfd.optim import finish_run, load_task, resume_run, start_run
from stl_lfd.optim.loop import run_remaining_trials, search_method
from stl_lfd.optim.methods.base import Planner, Problem, Request
from stl_lfd.optim.methods.plan_model import Plan
from stl_lfd.optim.methods.tuning import PlanSettings
from stl_lfd.optim.placements import spec_composition
from stl_lfd.optim.settings import Optimizer
from stl_lfd.optim.trials import Outcome, best_trial
from stl_lfd.stl import parse, split_spec
from tests.optim.test_run import small_task

BOUNDS = np.array([[0.0] * 4, [1.0] * 4])
PARTS = split_spec(parse("a > 0 & b > 0"), "new")


def planned_parts(x: np.ndarray) -> np.ndarray:
    """What the plan says of each part: a small box around (0.8, 0.2, 0.3, 0.6) satisfies both."""
    return np.array([0.15 - abs(x[0] - 0.8) - 0.3 * abs(x[2] - 0.3), 0.15 - abs(x[1] - 0.2) - 0.3 * abs(x[3] - 0.6)])


def executed_parts(x: np.ndarray) -> np.ndarray:
    """The execution: part b loses more the further x[2] is below 0.6 (contact the plan cannot
    see), so the plan's best points (x[2] = 0.3) fail; x[2] near 0.5 satisfies both parts."""
    return planned_parts(x) - np.array([0.0, 0.5 * max(0.0, 0.6 - x[2])])


def batched(parts):
    """A plan of one point as method `plan` asks for plans: `b x d` points -> `b x o`."""
    return lambda points: np.array([parts(x) for x in points])


def objective(parts):
    def evaluate(x):
        values = parts(x)
        return Outcome(PARTS.compose(values), components=dict(zip(PARTS.names, values.tolist())))

    return evaluate


def method(optimizer):
    return search_method(optimizer, Problem(BOUNDS, spec_composition(PARTS), planner=Planner(batched(planned_parts))))


def run(parts, optimizer, history=()):
    return run_remaining_trials(objective(parts), method(optimizer), list(history), lambda trial, payload: None)


def test_a_plan_is_memoised_and_a_point_without_one_is_nan():
    calls = []

    def score(points):
        calls.append(len(points))
        if np.any(points[:, 0] > 0.5):
            raise ValueError("no reference")
        return batched(planned_parts)(points)

    plan = Plan(score, BOUNDS)
    points = np.array([[0.1, 0.2, 0.3, 0.4], [0.9, 0.2, 0.3, 0.4], [0.2, 0.2, 0.3, 0.4]])
    first = plan(points)
    np.testing.assert_array_equal(first[[0, 2]], batched(planned_parts)(points[[0, 2]]))
    assert np.all(np.isnan(first[1]))
    assert calls == [3, 1, 1, 1]  # the batch failed: each point alone
    again = plan(points[::-1])
    assert len(calls) == 4 and np.array_equal(again, first[::-1], equal_nan=True)
    plan(np.array([[0.3, 0.2, 0.3, 0.4], [0.4, 0.2, 0.3, 0.4], [0.3, 0.2, 0.3, 0.4]]))
    assert calls[4:] == [2]  # new points in one batch, each once


def test_the_first_point_is_the_best_plan_the_search_finds():
    plan_search = method(Optimizer("plan", initial=1, trials=2, seed=0))
    [(x, phase)] = plan_search.propose(Request([], np.empty((0, 4)), 0, 1, 0))
    planned = [PARTS.compose(values) for values in plan_search.plan.memo.values()]
    assert PARTS.compose(planned_parts(x)) == pytest.approx(max(planned))
    assert PARTS.compose(planned_parts(x)) > 0  # the box is found by the plan search alone


def test_where_the_plan_is_exact_the_first_trial_satisfies():
    for seed in range(3):
        history = run(planned_parts, Optimizer("plan", initial=1, trials=2, seed=seed))
        assert history[0].satisfied and history[0].phase == "design", seed


@pytest.mark.slow
def test_where_the_plan_is_wrong_the_difference_is_learned_from_the_trials():
    for seed in range(3):
        history = run(executed_parts, Optimizer("plan", initial=4, trials=12, seed=seed))
        assert best_trial(history).satisfied, seed
        assert best_trial(history).x[2] > 0.45, seed  # well away from the plan's best, x[2] = 0.3


def test_method_plan_is_reproducible_and_resumes_exactly():
    optimizer = Optimizer("plan", initial=4, trials=6, seed=1)
    first = run(executed_parts, optimizer)
    assert np.array_equal([t.x for t in first], [t.x for t in run(executed_parts, optimizer)])
    resumed = run(executed_parts, optimizer, run(executed_parts, Optimizer("plan", initial=3, trials=3, seed=1)))
    assert np.array_equal([t.x for t in resumed], [t.x for t in first])
    assert all(np.all((t.x >= BOUNDS[0]) & (t.x <= BOUNDS[1])) for t in first)


def test_the_design_spreads_over_the_points_the_plan_satisfies():
    # the parts composed as recorded, so that the pool's best quarter is the one computed here
    history = run(executed_parts, Optimizer("plan", initial=4, trials=4, seed=0, tuning={"plan": PlanSettings(balance=False)}))
    assert [trial.phase for trial in history] == ["design"] * 4
    pool = method(Optimizer("plan", initial=4, trials=4, seed=0)).pool(0)
    pool_values = np.array([PARTS.compose(planned_parts(point)) for point in pool])
    satisfying = int(np.sum(pool_values > 0))
    planned = [PARTS.compose(planned_parts(trial.x)) for trial in history]
    assert planned[0] > 0  # the plan search's best
    # the pool's satisfying points come first; when they run out, points of its best quarter
    spread = planned[1:]
    assert all(value > 0 for value in spread[:satisfying]) and sum(value > 0 for value in spread) == min(satisfying, 3)
    assert all(value >= np.quantile(pool_values, 0.7) for value in spread)
    gaps = [np.linalg.norm(a.x - b.x) for i, a in enumerate(history) for b in history[:i]]
    assert min(gaps) > 0.05  # and none repeats another


def test_parallel_trials_spread_out_and_resume_exactly_in_the_middle_of_a_batch():
    optimizer = Optimizer("plan", initial=2, trials=6, seed=0, workers=2)
    first = run(executed_parts, optimizer)
    assert [trial.phase for trial in first] == ["design"] * 2 + ["plan"] * 4
    for a, b in ((first[2], first[3]), (first[4], first[5])):  # the two points of a batch
        assert np.max(np.abs(a.x - b.x)) >= PlanSettings().pending_spread
    resumed = run(executed_parts, optimizer, first[:3])
    assert np.array_equal([t.x for t in resumed], [t.x for t in first])


@pytest.mark.slow
def test_a_run_with_method_plan_scores_the_plan_on_the_kinematic_backend_and_resumes(tmp_path, learned_model_file):
    task = load_task(small_task(tmp_path, learned_model_file)).with_overrides(method="plan", initial=1, trials=4)
    whole = start_run(task, tmp_path / "whole")
    plan = Plan(whole.problem().planner.plan, whole.space.bounds)
    x = (whole.space.bounds[0] + whole.space.bounds[1]) / 2
    planned = plan(np.full((1, whole.space.dimension), 0.5))[0]
    executed = whole.objective(x)
    np.testing.assert_allclose(planned, list(executed.components.values()))  # the kinematic backend executes the plan
    finish_run(whole)
    trials = [json.loads(line) for line in (tmp_path / "whole" / "trials.jsonl").read_text().splitlines()]
    assert [trial["phase"] for trial in trials] == ["design"] + ["plan"] * 3
    assert trials[0]["robustness"] > whole.summary.initial_robustness
    finish_run(start_run(task.with_overrides(trials=2), tmp_path / "resumed"))
    finish_run(resume_run(tmp_path / "resumed", trials=4))
    resumed = [json.loads(line) for line in (tmp_path / "resumed" / "trials.jsonl").read_text().splitlines()]
    assert [trial["x"] for trial in resumed] == [trial["x"] for trial in trials]


def test_plans_scored_together_are_the_plans_scored_alone_and_the_kinematic_trials(tmp_path, learned_model_file):
    """A batch of plans (their references retrieved together) gives exactly each point's plan
    alone, and exactly the point's trial on the kinematic backend, whose difference from the
    plan method `plan` then learns as 0."""
    from stl_lfd.optim.inputs import resolve, task_models
    from stl_lfd.optim.objective import objective_for

    task = load_task(small_task(tmp_path, learned_model_file))
    space, objective = objective_for(resolve(task), task_models(resolve(task)))
    points = space.lower + np.random.default_rng(0).random((5, space.dimension)) * (space.upper - space.lower)
    plans = objective.plan_score()(points)
    assert plans.shape == (5, len(objective.composition.names))
    for x, values in zip(points, plans):
        assert np.array_equal(objective.plan_score()(x[None])[0], values)
        assert np.array_equal(list(objective(x).components.values()), values)


def test_kept_references_are_those_retrieved_anew_and_the_oldest_go_beyond_the_budget(tmp_path, learned_model_file, monkeypatch):
    """Plans through successive tracking models share the references of recent points: kept,
    they are exactly what a new retrieval gives; past the memory budget the oldest are dropped
    (and retrieved again when asked for)."""
    import stl_lfd.optim.objective as objectives
    import stl_lfd.optim.plans as plans
    from stl_lfd.optim.inputs import resolve, task_models

    task = load_task(small_task(tmp_path, learned_model_file))
    space, objective = objectives.objective_for(resolve(task), task_models(resolve(task)))
    points = space.lower + np.random.default_rng(1).random((4, space.dimension)) * (space.upper - space.lower)
    kept = objective.plans.references(points, keep=True)[0]
    fresh = objective.plans.references(points)[0]
    for a, b in zip(kept, fresh):
        assert a is not b and np.array_equal(a.times, b.times) and np.array_equal(a.positions, b.positions)
    assert all(a is b for a, b in zip(objective.plans.references(points[::-1], keep=True)[0], kept[::-1]))
    monkeypatch.setattr(plans, "PLANNED_REFERENCE_BYTES", 2.5 * plans.reference_bytes(kept[0]))
    again = objective.plans.references(points[:1], keep=True)[0][0]  # the latest used: kept
    assert again is kept[0] and len(objective.plans._references) == 2  # the oldest, points 3 and 2, dropped
    assert objective.plans.references(points[1:2], keep=True)[0][0] is kept[1]
    assert objective.plans.references(points[3:], keep=True)[0][0] is not kept[3]  # retrieved anew


def test_recordings_on_other_clocks_are_scored_apart_and_as_alone(tmp_path, learned_model_file):
    """`score_all` batches the recordings that share sample times; each outcome is exactly the
    recording's own `score`."""
    from stl_lfd.optim.inputs import resolve, task_models
    from stl_lfd.optim.objective import objective_for
    from stl_lfd.signals import SignalTable

    task = load_task(small_task(tmp_path, learned_model_file))
    space, objective = objective_for(resolve(task), task_models(resolve(task)))
    points = space.lower + np.random.default_rng(2).random((3, space.dimension)) * (space.upper - space.lower)
    recordings = [outcome.payload for outcome in objective.planned().evaluate_all([space.apply(objective.models, x) for x in points])]
    shorter = SignalTable(recordings[1].times[:-50], {name: values[:-50] for name, values in recordings[1].columns.items()}, source="shorter")
    mixed = [recordings[0], shorter, recordings[2]]
    for together, signals in zip(objective.score_all(mixed), mixed):
        alone = objective.score_all([signals])[0]
        assert together.robustness == alone.robustness and together.components == alone.components and together.payload is signals
