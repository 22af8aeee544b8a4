"""Whole runs from task files on the kinematic backend: the run directory, resume, refusals."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.errors import ConfigError, SpecError
from stl_lfd.optim import RunDirectory, build_search_space, finish_run, load_task, resume_run, start_run
from tests.conftest import ROOT

runner = CliRunner()


def small_task(tmp_path: Path, model_file: Path, spec: str = "phi1", duration: float = 22, extra: str = "") -> Path:
    path = tmp_path / f"{spec}.yaml"
    path.write_text(
        f"name: small\nspec: {ROOT / 'specs' / (spec + '.stl')}\nmodel: {model_file}\nbackend: kinematic\n"
        f"duration: {duration}\nrate: 50\n"
        "parameters:\n  means: {components: [2, 3]}\n  durations: {components: all}\n"
        "optimizer: {method: stl, initial: 3, trials: 5, seed: 2}\n" + extra
    )
    return path


@pytest.mark.slow
def test_a_run_writes_its_directory_as_it_goes(tmp_path, learned_model_file):
    task = load_task(small_task(tmp_path, learned_model_file))
    summary = finish_run(start_run(task, tmp_path / "run"))
    run = tmp_path / "run"
    assert {path.name for path in run.iterdir()} == {
        "task.yaml",
        "inputs.json",
        ".lock",
        "model.npz",
        "trials.jsonl",
        "signals",
        "best_model.npz",
        "summary.json",
    }
    lines = (run / "trials.jsonl").read_text().splitlines()
    assert len(lines) == 5
    first = json.loads(lines[0])
    assert set(first) >= {"trial", "parameters", "robustness", "satisfied", "wall_seconds", "status"}
    assert len(first["parameters"]) == 12
    assert sorted(path.name for path in (run / "signals").iterdir()) == ["initial.csv"] + [f"trial-000{n}.csv" for n in range(1, 6)]
    assert json.loads((run / "summary.json").read_text()) == summary.to_json()
    assert summary.trials == 5 and summary.complete
    assert summary.initial_robustness < 0  # the learned skill violates phi1
    best = max(json.loads(line)["robustness"] for line in lines)
    assert summary.best_robustness == best
    assert set(summary.to_json()) >= {"initial_robustness", "best_robustness", "best_trial", "satisfied", "trials", "wall_seconds"}
    space = build_search_space(RunDirectory(run).models(), task.parameters)
    assert [trial.phase for trial in RunDirectory(run).trials()] == ["sobol"] * 3 + ["stl"] * 2
    for trial in RunDirectory(run).trials():  # the Sobol points and the acquisition's maximisers
        assert np.all((trial.x >= space.lower) & (trial.x <= space.upper)), trial.trial


@pytest.mark.slow
def test_a_killed_run_resumes_without_repeating_or_losing_trials(tmp_path, learned_model_file):
    task = load_task(small_task(tmp_path, learned_model_file))
    finish_run(start_run(task, tmp_path / "whole"))
    interrupted = tmp_path / "interrupted"
    finish_run(start_run(task.with_overrides(trials=4), interrupted))
    # a kill while the fourth line was being written leaves a partial line behind
    trials_file = interrupted / "trials.jsonl"
    lines = trials_file.read_text().splitlines()
    trials_file.write_text("\n".join(lines[:3]) + "\n" + lines[3][:40])
    summary = finish_run(resume_run(interrupted, trials=5))
    assert summary.trials == 5
    resumed = [json.loads(line) for line in trials_file.read_text().splitlines()]
    whole = [json.loads(line) for line in (tmp_path / "whole" / "trials.jsonl").read_text().splitlines()]
    assert [trial["trial"] for trial in resumed] == [1, 2, 3, 4, 5]
    assert [trial["x"] for trial in resumed] == [trial["x"] for trial in whole]
    assert [trial["robustness"] for trial in resumed] == [trial["robustness"] for trial in whole]


def test_a_spec_looking_past_the_rollout_is_refused_before_any_trial(tmp_path, learned_model_file):
    task = load_task(small_task(tmp_path, learned_model_file, duration=15))
    with pytest.raises(ConfigError, match="looks 17 s ahead but rollouts last 15 s"):
        start_run(task, tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_a_spec_on_signals_that_rollouts_do_not_record_is_refused(tmp_path, learned_model_file):
    spec = tmp_path / "torque.stl"
    spec.write_text("G torque < 1\n")
    task = load_task(small_task(tmp_path, learned_model_file)).with_overrides(spec=spec)
    with pytest.raises(SpecError, match="signal torque is not recorded"):
        start_run(task, tmp_path / "run")
    assert not (tmp_path / "run").exists() and not list(tmp_path.glob(".run.*"))


@pytest.mark.slow
def test_cli_optimize_prints_the_summary_and_protects_existing_runs(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    out = tmp_path / "cli-run"
    result = runner.invoke(app, ["optimize", str(task), "--out", str(out), "--iterations", "4", "--init", "2", "--seed", "5"])
    assert result.exit_code == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["trials"] == 4 and summary["initial_trials"] == 2 and summary["seed"] == 5
    assert "unoptimised skill: robustness" in result.stderr and "4/5" not in result.stderr
    again = runner.invoke(app, ["optimize", str(task), "--out", str(out)])
    assert again.exit_code == 9 and "exists; continue it with --resume" in again.stderr
    changed = runner.invoke(app, ["optimize", str(task), "--out", str(out), "--resume", "--seed", "1"])
    assert changed.exit_code == 9 and "--seed cannot change on --resume" in changed.stderr
    extended = runner.invoke(app, ["optimize", str(task), "--out", str(out), "--resume", "--iterations", "5"])
    assert extended.exit_code == 0, extended.stderr
    assert json.loads(extended.stdout)["trials"] == 5
    assert "resuming after trial 4" in extended.stderr
    quiet = runner.invoke(app, ["optimize", str(task), "--out", str(out), "--resume", "--iterations", "6", "--quiet"])
    assert quiet.exit_code == 0, quiet.stderr
    lines = quiet.stderr.splitlines()
    assert len(lines) == 2 and "trials 6 to 6 of method" in lines[0] and lines[1].startswith("best: trial")


@pytest.mark.slow
def test_replay_of_a_run_uses_its_spec_and_best_trial(tmp_path, learned_model_file):
    out = tmp_path / "run"
    finish_run(start_run(load_task(small_task(tmp_path, learned_model_file)), out))
    summary = json.loads((out / "summary.json").read_text())
    video = tmp_path / "best.gif"
    result = runner.invoke(app, ["replay", str(out), "--video", str(video), "--duration", "0.5"])
    assert result.exit_code == 0, result.stderr
    assert video.exists() and "new robustness of" in result.stderr
    missing = runner.invoke(app, ["replay", str(out), "--trial", "9", "--video", str(video)])
    assert missing.exit_code == 9 and "no trial 9" in missing.stderr
    assert summary["best_trial"] is not None


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_trials_and_says_how_to_resume(tmp_path, learned_model_file, monkeypatch):
    from stl_lfd.optim import objective as run_module

    task = small_task(tmp_path, learned_model_file)
    out = tmp_path / "interrupted"
    original = run_module.SkillObjective.__call__
    calls = []

    def interrupt_on_third(self, x, trial=0):
        calls.append(x)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(self, x, trial)

    monkeypatch.setattr(run_module.SkillObjective, "__call__", interrupt_on_third)
    result = runner.invoke(app, ["optimize", str(task), "--out", str(out)])
    assert result.exit_code == 130
    assert "--resume" in result.stderr and "Traceback" not in result.stderr
    assert len((out / "trials.jsonl").read_text().splitlines()) == 2
    monkeypatch.setattr(run_module.SkillObjective, "__call__", original)
    resumed = runner.invoke(app, ["optimize", str(task), "--out", str(out), "--resume"])
    assert resumed.exit_code == 0, resumed.stderr
    assert json.loads(resumed.stdout)["trials"] == 5


@pytest.mark.slow
@pytest.mark.parametrize("semantics", ["classic", "new"])
def test_recorded_parts_compose_to_the_recorded_robustness_exactly(tmp_path, learned_model_file, semantics):
    from stl_lfd.stl import load_spec, split_spec

    task = load_task(small_task(tmp_path, learned_model_file, extra=f"semantics: {semantics}\n")).with_overrides(method="stl")
    summary = finish_run(start_run(task, tmp_path / "run"))
    parts = split_spec(load_spec(ROOT / "specs" / "phi1.stl"), semantics)
    trials = [json.loads(line) for line in (tmp_path / "run" / "trials.jsonl").read_text().splitlines()]
    assert [trial["phase"] for trial in trials] == ["sobol"] * 3 + ["stl"] * 2
    for trial in trials:
        assert list(trial["components"]) == list(parts.names)
        assert parts.compose(list(trial["components"].values())) == trial["robustness"]
    assert parts.compose(list(summary.initial_components.values())) == summary.initial_robustness


@pytest.mark.slow
def test_routes_are_recorded_with_each_trial_and_a_resumed_run_proposes_the_same_points(tmp_path, learned_model_file):
    from stl_lfd.signals import read_signal_csv
    from stl_lfd.stl import Spec

    spec = tmp_path / "implication.stl"
    spec.write_text("F[0, 20] x > 0.45 & G (y > 0.1 -> z < 0.35)\n")
    task = load_task(small_task(tmp_path, learned_model_file)).with_overrides(spec=spec, method="stl")
    finish_run(start_run(task, tmp_path / "whole"))
    trials = [json.loads(line) for line in (tmp_path / "whole" / "trials.jsonl").read_text().splitlines()]
    routes = {name: Spec.parse(name) for name in ("G !y > 0.1", "G z < 0.35")}
    for trial in trials:
        table = read_signal_csv(tmp_path / "whole" / "signals" / f"trial-{trial['trial']:04d}.csv")
        expected = {name: route.robustness(table.columns, table.times) for name, route in routes.items()}
        assert trial["routes"] == pytest.approx(expected, abs=1e-9)  # the CSV holds rounded signals
    assert [trial.routes for trial in RunDirectory(tmp_path / "whole").trials()] == [trial["routes"] for trial in trials]
    finish_run(start_run(task.with_overrides(trials=4), tmp_path / "resumed"))
    finish_run(resume_run(tmp_path / "resumed", trials=5))
    resumed = [json.loads(line) for line in (tmp_path / "resumed" / "trials.jsonl").read_text().splitlines()]
    assert [trial["x"] for trial in resumed] == [trial["x"] for trial in trials]


@pytest.mark.slow
def test_a_spec_without_routes_records_none(tmp_path, learned_model_file):
    finish_run(start_run(load_task(small_task(tmp_path, learned_model_file)), tmp_path / "run"))
    assert all("routes" not in json.loads(line) for line in (tmp_path / "run" / "trials.jsonl").read_text().splitlines())


def test_a_run_on_transitions_models_paths_and_resumes_exactly(tmp_path, learned_model_file):
    extra = "  transitions: band\n"
    path = small_task(tmp_path, learned_model_file)
    path.write_text(
        path.read_text()
        .replace("optimizer: {method: stl, initial: 3, trials: 5, seed: 2}", "optimizer: {method: stl, initial: 3, trials: 6, seed: 2}")
        .replace("  durations: {components: all}\n", "  durations: {components: all}\n" + extra)
    )
    task = load_task(path).with_overrides(method="stl")
    whole = start_run(task, tmp_path / "whole")
    features = whole.problem().features
    assert features is not None and features.dimension == 6 + 6 + 6  # means, five starts and the end, states
    finish_run(whole)
    trials = [json.loads(line) for line in (tmp_path / "whole" / "trials.jsonl").read_text().splitlines()]
    assert [trial["phase"] for trial in trials][3:] != ["sobol"] * 3
    finish_run(start_run(task.with_overrides(trials=4), tmp_path / "resumed"))
    finish_run(resume_run(tmp_path / "resumed", trials=6))
    resumed = [json.loads(line) for line in (tmp_path / "resumed" / "trials.jsonl").read_text().splitlines()]
    assert [trial["x"] for trial in resumed] == [trial["x"] for trial in trials]
