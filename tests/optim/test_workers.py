"""Parallel trials: batches of `workers` trials, proposed together and run by worker processes."""

import json

import numpy as np
import pytest
import torch

from stl_lfd.errors import ConfigError
from stl_lfd.optim import finish_run, load_task, resume_run, start_run
from stl_lfd.optim.loop import batch_of, next_points, run_remaining_trials, search_method
from stl_lfd.optim.methods.base import Problem
from stl_lfd.optim.methods.gp import fit_multi_output_gp
from stl_lfd.optim.methods.posterior import PartsPosterior
from stl_lfd.optim.placements import spec_composition
from stl_lfd.optim.settings import Optimizer
from tests.optim.test_composite import BOUNDS, PARTS, conjunction_objective
from tests.optim.test_run import small_task


def in_order(points):
    """A `submit` that runs a batch in this process (what the worker pool does in parallel)."""
    outcomes = [conjunction_objective(x) for x, _ in points]
    return lambda: outcomes


def method(optimizer):
    return search_method(optimizer, Problem(BOUNDS, spec_composition(PARTS)))


def run(optimizer, history=(), submit=in_order):
    return run_remaining_trials(conjunction_objective, method(optimizer), list(history), lambda trial, payload: None, submit)


def test_batches_split_the_initial_trials_and_then_the_rest():
    optimizer = Optimizer("stl", initial=5, trials=12, workers=2)
    assert [batch_of(index, optimizer) for index in range(12)] == [
        (0, 2), (0, 2), (2, 4), (2, 4), (4, 5), (5, 7), (5, 7), (7, 9), (7, 9), (9, 11), (9, 11), (11, 12),
    ]  # fmt: skip
    assert [batch_of(index, Optimizer("stl", initial=3, trials=5)) for index in range(5)] == [(i, i + 1) for i in range(5)]


@pytest.mark.slow
def test_one_worker_proposes_from_the_whole_history_and_more_propose_a_batch_ahead():
    optimizer = Optimizer("stl", initial=4, trials=7, seed=2)
    sequential = run(optimizer, submit=None)
    assert [trial.x.tolist() for trial in run(optimizer)] == [trial.x.tolist() for trial in sequential]
    history = sequential[:6]
    # with 2 workers, the batch of trials 7-8 is proposed while trials 5-6 run: from trials 1-4,
    # with 5 and 6 pending, whether 5-6 are recorded yet or not
    parallel = Optimizer("stl", initial=4, trials=8, seed=2, workers=2)
    ahead = next_points(history[:4], method(parallel), [trial.x for trial in history[4:6]])
    after = next_points(history, method(parallel))
    assert [x.tolist() for x, _ in ahead] == [x.tolist() for x, _ in after] and len(after) == 2


@pytest.mark.slow
def test_a_batch_is_reproducible_and_a_resume_inside_it_continues_exactly():
    optimizer = Optimizer("stl", initial=4, trials=10, seed=1, workers=3)
    whole = run(optimizer)
    assert [trial.phase for trial in whole] == ["sobol"] * 4 + ["stl"] * 6
    assert [trial.x.tolist() for trial in run(optimizer)] == [trial.x.tolist() for trial in whole]
    resumed = run(optimizer, whole[:5])  # killed after the first trial of a batch of three
    assert [trial.x.tolist() for trial in resumed] == [trial.x.tolist() for trial in whole]
    batch = next_points(whole[:4], method(optimizer))
    assert len(batch) == 3 and len({tuple(np.round(x, 6)) for x, _ in batch}) == 3  # three distinct points


@pytest.mark.slow
def test_a_pending_point_keeps_the_mean_and_shrinks_the_variance_around_it():
    rng = np.random.default_rng(0)
    X = rng.random((12, 2))
    parts = np.column_stack([np.sin(3 * X[:, 0]), X[:, 1] ** 2])
    posterior = PartsPosterior(fit_multi_output_gp(X, parts))
    pending = torch.tensor([[0.5, 0.5]], dtype=torch.float64)
    near = torch.tensor([[0.5, 0.5], [0.52, 0.49], [0.95, 0.05]], dtype=torch.float64)
    mean, std = posterior(near)
    pending_mean, pending_std = posterior.with_pending(pending)(near)
    torch.testing.assert_close(pending_mean, mean)
    assert torch.all(pending_std[:2] < 0.9 * std[:2]) and torch.all(pending_std <= std + 1e-12)


def test_methods_that_propose_one_point_refuse_parallel_trials():
    with pytest.raises(ConfigError, match="method pi proposes one trial at a time"):
        Optimizer("pi", workers=2)
    with pytest.raises(ConfigError, match="'optimizer.workers' must be from 1 to 256"):
        Optimizer("stl", workers=0)


@pytest.mark.slow
def test_a_run_with_two_workers_records_its_trials_in_order_and_resumes(tmp_path, learned_model_file):
    task = load_task(small_task(tmp_path, learned_model_file, extra="")).with_overrides(workers=2, trials=6, initial=3)
    single = load_task(small_task(tmp_path, learned_model_file)).with_overrides(trials=6, initial=3)
    finish_run(start_run(task.with_overrides(trials=4), tmp_path / "parallel"))
    finish_run(resume_run(tmp_path / "parallel", trials=6))
    finish_run(start_run(single, tmp_path / "single"))
    parallel, sequential = ([json.loads(line) for line in (tmp_path / name / "trials.jsonl").read_text().splitlines()] for name in ("parallel", "single"))
    assert [trial["trial"] for trial in parallel] == [1, 2, 3, 4, 5, 6]
    # the Sobol trials do not depend on the batches; every trial was executed and scored
    assert [(t["x"], t["robustness"]) for t in parallel[:3]] == [(t["x"], t["robustness"]) for t in sequential[:3]]
    assert all(trial["status"] == "ok" and (tmp_path / "parallel" / "signals" / f"trial-{trial['trial']:04d}.csv").exists() for trial in parallel)
    assert json.loads((tmp_path / "parallel" / "summary.json").read_text())["trials"] == 6


@pytest.mark.slow
@pytest.mark.heavy
def test_ctrl_c_stops_the_workers_and_the_run_resumes(tmp_path, learned_model_file):
    import signal
    import subprocess
    import sys
    from pathlib import Path

    from tests.processes import deliverable_sigint, interrupt, wait_for

    task = small_task(tmp_path, learned_model_file)
    stlopt = str(Path(sys.executable).parent / "stlopt")
    command = [stlopt, "optimize", str(task), "--out", str(tmp_path / "run"), "--workers", "2"]
    process = subprocess.Popen(command + ["-N", "500"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=deliverable_sigint)
    trials = tmp_path / "run" / "trials.jsonl"
    wait_for(lambda: trials.exists() and len(trials.read_text().splitlines()) >= 6, timeout=300)
    _, err = interrupt(process)  # returns only once nothing the run started holds its output
    assert process.returncode == -signal.SIGINT and "Traceback" not in err, err
    kept = len(trials.read_text().splitlines())
    resumed = subprocess.run(command + ["-N", str(kept + 3), "--resume"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert [json.loads(line)["trial"] for line in trials.read_text().splitlines()] == list(range(1, kept + 4))


def _started_with_workers(tmp_path, learned_model_file):
    import subprocess
    import sys
    from pathlib import Path

    from tests.processes import wait_for, worker_processes

    task = small_task(tmp_path, learned_model_file)
    stlopt = str(Path(sys.executable).parent / "stlopt")
    command = [stlopt, "optimize", str(task), "--out", str(tmp_path / "run"), "--workers", "2"]
    process = subprocess.Popen(command + ["-N", "500"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    trials = tmp_path / "run" / "trials.jsonl"
    wait_for(lambda: trials.exists() and len(trials.read_text().splitlines()) >= 4, timeout=300)
    workers = worker_processes(process.pid)
    assert len(workers) == 2
    return process, command, trials, workers


@pytest.mark.slow
@pytest.mark.heavy
def test_a_killed_worker_stops_the_run_with_one_line_and_it_resumes(tmp_path, learned_model_file):
    import os
    import signal
    import subprocess

    process, command, trials, workers = _started_with_workers(tmp_path, learned_model_file)
    os.kill(workers[0], signal.SIGKILL)
    out, err = process.communicate(timeout=120)
    assert process.returncode != 0 and "Traceback" not in err, err
    assert [line for line in err.splitlines() if line.startswith("error")] == [next(line for line in err.splitlines() if "a worker process died" in line)], err
    from stl_lfd.optim.runs.lock import RunLock

    RunLock.acquire(tmp_path / "run", tmp_path / "run").release()  # not held: the next command may write
    kept = len(trials.read_text().splitlines())
    resumed = subprocess.run(command + ["-N", str(kept + 2), "--resume"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert [json.loads(line)["trial"] for line in trials.read_text().splitlines()] == list(range(1, kept + 3))


@pytest.mark.slow
@pytest.mark.heavy
def test_the_workers_end_when_the_main_process_is_killed(tmp_path, learned_model_file):
    import os
    import signal

    from tests.processes import alive, wait_for

    process, _, _, workers = _started_with_workers(tmp_path, learned_model_file)
    os.kill(process.pid, signal.SIGKILL)
    process.communicate(timeout=60)
    wait_for(lambda: not any(alive(pid) for pid in workers), timeout=30)
