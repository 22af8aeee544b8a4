"""Method plan through the tracking model: a run on a robot that lags and sags behind its
references learns how it tracks (kept in tracking.json), a resumed run proposes what an
uninterrupted one did, and a backend that plays the plan back learns nothing."""

import json

import numpy as np
import pytest
from scipy.signal import lfilter

import stl_lfd.optim.objective as objective_module
from stl_lfd.errors import RunError
from stl_lfd.optim import finish_run, load_task, resume_run, start_run
from stl_lfd.optim.tracking_fit import FOLLOWS_THE_PLAN, TRACKING_FILE, read_tracking, used
from stl_lfd.signals import SignalTable
from stl_lfd.sim.backend import Capabilities
from stl_lfd.sim.kinematic import KinematicBackend
from stl_lfd.sim.reference import Rollout
from tests.optim.test_run import small_task

LAG, SAG = 0.25, 0.012  # s, m


class SaggingRobot(KinematicBackend):
    """Follows the reference through a first-order lag and sits SAG below it."""

    capabilities = Capabilities()

    def run(self, reference, scene, rate, observer=None):
        rollout = super().run(reference, scene, rate, observer)
        columns = dict(rollout.signals.columns)
        keep = np.exp(-1 / (rate * LAG))
        for name in "xyz":
            start = columns[name][0]
            columns[name] = lfilter([1 - keep], [1, -keep], columns[name] - start) + start - (SAG if name == "z" else 0.0)
        return Rollout(SignalTable(rollout.signals.times, columns, source="sagging robot"), rollout.tracking_error)


@pytest.fixture
def sagging(monkeypatch):
    original = objective_module.new_backend
    monkeypatch.setattr(objective_module, "new_backend", lambda name, options=None: SaggingRobot() if name == "kinematic" else original(name, options))


def plan_task(tmp_path, learned_model_file, trials):
    task = load_task(small_task(tmp_path, learned_model_file))
    return task.with_overrides(method="plan", initial=2, trials=trials, seed=5)


def trial_points(folder):
    return [json.loads(line)["x"] for line in (folder / "trials.jsonl").read_text().splitlines()]


@pytest.mark.slow
def test_a_sagging_robot_is_learned_and_a_resumed_run_proposes_the_same(tmp_path, learned_model_file, sagging, monkeypatch):
    whole = tmp_path / "whole"
    finish_run(start_run(plan_task(tmp_path, learned_model_file, 4), whole))
    record = read_tracking(whole)
    trials, model = record.trials, record.model
    assert trials == [0, 1, 2, 3, 4]  # the unoptimised skill and every trial: the record is refitted when the run ends
    assert model.kind_ in ("offset", "filter", "clocked filter")
    assert model.offsets_[2] == pytest.approx(-SAG, abs=1e-3)
    assert np.all(model.heldout_rms_ < 0.2 * model.plan_rms_)
    assert record.used

    assert set(record.errors) == {0, 1, 2, 3, 4} and all(model_error < plan_error for plan_error, model_error in record.errors.values())
    robustness = {json.loads(line)["trial"]: json.loads(line)["robustness"] for line in (whole / "trials.jsonl").read_text().splitlines()}
    best, paths = record.best
    assert best == max(robustness, key=robustness.get) and len(paths.times) <= 501 and paths.executed.shape == paths.predicted.shape == (len(paths.times), 3)
    assert np.sqrt(np.mean((paths.predicted - paths.executed) ** 2)) < np.sqrt(np.mean((paths.planned - paths.executed) ** 2))

    from stl_lfd.report import write_report

    def no_objective(*args, **kwargs):
        raise AssertionError("the report rebuilt the objective")

    monkeypatch.setattr(objective_module, "objective_for", no_objective)  # the figure reads tracking.json alone
    index, pictures = write_report(whole)
    assert whole / "report" / "tracking.png" in pictures
    assert "Method plan scored its candidates by this prediction" in index.read_text()
    (whole / TRACKING_FILE).write_text('{"trials": [0')
    with pytest.raises(RunError, match="tracking.json: damaged"):
        write_report(whole)

    halves = tmp_path / "halves"
    finish_run(start_run(plan_task(tmp_path, learned_model_file, 3), halves))
    finish_run(resume_run(halves, trials=4))
    assert np.allclose(trial_points(halves), trial_points(whole), rtol=0, atol=1e-12)


def test_plans_go_through_the_model_only_where_the_robot_departs_from_them():
    from stl_lfd.sim.tracking_model import TrackingModel

    assert not used(TrackingModel(plan_rms_=np.array([0.3, 0.2, 0.9]) * FOLLOWS_THE_PLAN))  # PyBullet: hundredths of a mm
    assert used(TrackingModel(kind_="offset", plan_rms_=np.array([0.0, 0.0, 2.0]) * FOLLOWS_THE_PLAN))


@pytest.mark.slow
def test_a_backend_that_plays_the_plan_learns_no_tracking(tmp_path, learned_model_file):
    folder = tmp_path / "run"
    finish_run(start_run(plan_task(tmp_path, learned_model_file, 3), folder))
    assert not (folder / TRACKING_FILE).exists()


def test_a_model_that_is_the_plan_is_not_used_however_far_the_robot_strays():
    from stl_lfd.sim.tracking_model import TrackingModel

    assert not used(TrackingModel(kind_="plan", plan_rms_=np.array([0.0, 0.0, 2.0]) * FOLLOWS_THE_PLAN))  # noise alone


def test_a_run_in_memory_learns_from_its_signals_as_a_run_directory_keeps_them(tmp_path):
    from stl_lfd.optim.runs.store import MemoryRun
    from stl_lfd.signals import read_signal_csv, write_signal_csv

    signals = SignalTable(np.arange(50) / 50, {name: np.random.default_rng(1).normal(size=50) / 3 for name in "xyz"})
    write_signal_csv(signals, tmp_path / "signals.csv")
    on_disk, in_memory = read_signal_csv(tmp_path / "signals.csv"), MemoryRun(signals).recorded_signals(0)
    assert np.array_equal(in_memory.times, on_disk.times)
    assert all(np.array_equal(in_memory.columns[name], on_disk.columns[name]) for name in "xyz")
