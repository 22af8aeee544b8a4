"""Trials run elsewhere: `stlopt ask` and `stlopt tell` (kinematic executions in the test)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.errors import RunError, SignalError
from stl_lfd.optim import finish_run, load_task, start_run
from stl_lfd.optim.inputs import resolve
from stl_lfd.optim.runs.asktell import ask, ask_new, tell
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.runs.resume import inputs_record
from stl_lfd.optim.task import Overrides
from stl_lfd.signals import write_signal_csv
from stl_lfd.sim import Command, execute, load_scene, read_reference_csv

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()
TIGHT_SCENE = "description: tight\nsafety:\n  workspace: {lower: [0.2, -0.6, 0.1], upper: [0.8, 0.6, 0.8]}\n  max_speed: 0.6\n"


def task_file(tmp_path, model_file, trials=5, scene="free_space", spec="phi1", transitions="none", method="stl"):
    path = tmp_path / "task.yaml"
    path.write_text(
        f"name: robot\nspec: {ROOT / 'specs' / (spec + '.stl')}\nmodel: {model_file}\nbackend: kinematic\nscene: {scene}\nduration: 22\nrate: 50\n"
        f"parameters:\n  means: {{components: [2, 3]}}\n  durations: {{components: all}}\n  transitions: {transitions}\n"
        f"optimizer: {{method: {method}, initial: 2, trials: {trials}, seed: 4}}\n"
    )
    return path


def execute_kinematically(reference_path, scene="free_space", rate=50.0, name="signals.csv"):
    """What an executor does: read the reference, execute it, write the signals beside it."""
    signals = execute(read_reference_csv(reference_path), load_scene(scene), "kinematic", rate).signals
    path = Path(reference_path).parent / name
    write_signal_csv(signals, path, digits=17)
    return path


def start(tmp_path, model_file, **options):
    task = load_task(task_file(tmp_path, model_file, **options))
    return task, ask_new(resolve(task), tmp_path / "asked", inputs_record(task, Overrides(), resolve(task)))


def loop(run, scene="free_space"):
    while (asked := ask(run)) is not None:
        tell(run, execute_kinematically(asked.reference, scene))


def recorded(run):
    trials = [json.loads(line) for line in (run / "trials.jsonl").read_text().splitlines()]
    return [(trial["x"], trial["robustness"], trial["status"], trial["error"]) for trial in trials]


@pytest.mark.slow
# with the band, method stl models paths; method plan scores plans in the asking process
@pytest.mark.parametrize(("transitions", "method"), [("none", "stl"), ("band", "stl"), ("none", "plan")])
def test_an_ask_tell_loop_gives_the_trials_of_optimize(tmp_path, learned_model_file, transitions, method):
    task, first = start(tmp_path, learned_model_file, transitions=transitions, method=method)
    assert first.trial == 0 and first.reference == tmp_path / "asked" / "executions" / "initial" / "reference.csv"
    tell(tmp_path / "asked", execute_kinematically(first.reference))
    loop(tmp_path / "asked")
    finish_run(start_run(task, tmp_path / "optimized"))
    assert recorded(tmp_path / "asked") == recorded(tmp_path / "optimized")
    asked, optimized = (json.loads((tmp_path / name / "summary.json").read_text()) for name in ("asked", "optimized"))
    for key in ("initial_robustness", "best_robustness", "best_trial", "trials", "complete"):
        assert asked[key] == optimized[key]
    assert asked["executed_by"] == "stlopt ask/tell" and optimized["executed_by"] == "kinematic"  # the task's backend did not run the trials
    from stl_lfd.report import explain
    from stl_lfd.report.run_data import load_run

    run = load_run(tmp_path / "asked")
    assert dict(explain.task_rows(run))["execution"].startswith("executed elsewhere and told (stlopt ask/tell)")
    assert "what ran on the robot is not replayed" in explain.commands(run)[0][1]
    assert ask(tmp_path / "asked") is None


def test_the_initial_points_are_handed_out_without_loading_torch(tmp_path, learned_model_file):
    task, first = start(tmp_path, learned_model_file)
    run = RunDirectory(tmp_path / "asked")
    from stl_lfd.optim.methods.base import sobol_points
    from stl_lfd.optim.space import build_search_space

    bounds = build_search_space(run.models(), task.parameters).bounds
    assert (run.initial_design() == sobol_points(bounds, 2, 4)).all()
    tell(tmp_path / "asked", execute_kinematically(first.reference))
    script = "import sys; from stl_lfd.optim.runs.asktell import ask; asked = ask(sys.argv[1]); print(asked.trial, asked.phase, 'torch' in sys.modules)"
    printed = subprocess.run([sys.executable, "-c", script, str(tmp_path / "asked")], capture_output=True, text=True, cwd=ROOT)
    assert printed.stdout.split() == ["1", "sobol", "False"], printed.stderr
    assert json.loads((tmp_path / "asked" / "pending.json").read_text())["pending"][0]["x"] == list(run.initial_design()[0])


@pytest.mark.slow
def test_unsafe_trials_are_refused_as_optimize_refuses_them(tmp_path, learned_model_file):
    scene = tmp_path / "tight.yaml"
    scene.write_text(TIGHT_SCENE)
    task, first = start(tmp_path, learned_model_file, trials=8, scene=str(scene))
    tell(tmp_path / "asked", execute_kinematically(first.reference, str(scene)))
    refused = []
    while (asked := ask(tmp_path / "asked", on_refused=refused.append)) is not None:
        tell(tmp_path / "asked", execute_kinematically(asked.reference, str(scene)))
    assert refused and all(trial.error.startswith("unsafe reference, not executed") for trial in refused)
    assert not any((tmp_path / "asked" / "executions" / f"trial-{trial.trial:04d}").exists() for trial in refused)
    fake = ROOT / "tests" / "executors" / "fake.py"
    command = task.with_overrides(backend="command", command=Command.parse(f"{sys.executable} {fake} {{reference}} {{signals}}"))
    finish_run(start_run(command, tmp_path / "optimized"))
    assert recorded(tmp_path / "asked") == recorded(tmp_path / "optimized")


@pytest.mark.slow
def test_asking_again_gives_the_same_trial_and_a_killed_tell_loses_nothing(tmp_path, learned_model_file, monkeypatch):
    _, first = start(tmp_path, learned_model_file)
    run = tmp_path / "asked"
    tell(run, execute_kinematically(first.reference))
    asked = ask(run)
    again = ask(run)
    assert (again.trial, again.reference, again.again) == (asked.trial, asked.reference, True)
    signals = execute_kinematically(asked.reference)

    def killed(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(RunDirectory, "clear_pending", killed)
    with pytest.raises(KeyboardInterrupt):
        tell(run, signals)
    monkeypatch.undo()
    following = ask(run)
    assert following.trial == asked.trial + 1 and not following.again
    assert [trial[0] for trial in recorded(run)] == [json.loads((run / "trials.jsonl").read_text().splitlines()[0])["x"]]


@pytest.mark.slow
def test_telling_the_wrong_thing_is_a_clear_error_and_keeps_the_trial_pending(tmp_path, learned_model_file):
    _, first = start(tmp_path, learned_model_file, spec="phi3")
    run = tmp_path / "asked"
    with pytest.raises(RunError, match="the run waits for the signals of its unoptimised skill"):
        RunDirectory.open(run).summary()
    initial = execute_kinematically(first.reference)
    tell(run, initial)
    with pytest.raises(RunError, match=r"no trial is pending; hand out the next one with: stlopt ask"):
        tell(run, initial)
    trial_one = ask(run)
    tell(run, execute_kinematically(trial_one.reference))
    trial_two = ask(run)
    with pytest.raises(RunError, match=r"trial-0001/signals.csv: belongs to trial-0001 of the run, but trial 2 is pending"):
        tell(run, trial_one.reference.parent / "signals.csv")
    elsewhere = tmp_path / "copy.csv"
    shutil.copy(trial_one.reference.parent / "signals.csv", elsewhere)
    with pytest.raises(RunError, match=r"copy.csv: these signals follow the reference of trial-0001 .* not that of the pending trial 2"):
        tell(run, elsewhere)
    short = tmp_path / "short.csv"
    short.write_text(_first_lines(execute_kinematically(trial_two.reference, name="full.csv"), 50))
    with pytest.raises(SignalError, match=r"short.csv: the signals cover 0 to 0.96 s, but the rollout lasts 0 to 22 s"):
        tell(run, short)
    no_force = tmp_path / "no_force.csv"
    lines = (trial_two.reference.parent / "full.csv").read_text().splitlines()
    force = lines[0].split(",").index("force")
    no_force.write_text("\n".join(",".join(value for index, value in enumerate(line.split(",")) if index != force) for line in lines) + "\n")
    with pytest.raises(SignalError, match=r"no_force.csv: no column force, which the spec needs"):
        tell(run, no_force)
    assert [entry.trial for entry in RunDirectory.open(run).pending()] == [2]
    told = tell(run, None, failure="protective stop")
    assert told.trial.status == "failed" and told.trial.error == "execution failed: protective stop"
    assert ask(run).trial == 3


def _first_lines(path, count):
    return "\n".join(Path(path).read_text().splitlines()[:count]) + "\n"


@pytest.mark.slow
def test_the_commands_print_paths_and_robustness_for_scripts(tmp_path, learned_model_file):
    task = task_file(tmp_path, learned_model_file, trials=2)
    run = tmp_path / "run"
    result = runner.invoke(app, ["ask", str(task), "--out", str(run)])
    assert result.exit_code == 0, result.stderr
    reference = Path(result.stdout.strip())
    assert reference == run / "executions" / "initial" / "reference.csv" and "stlopt tell" in result.stderr
    assert runner.invoke(app, ["ask", str(task), "--out", str(run)]).stdout.strip() == str(reference)
    assert runner.invoke(app, ["ask", str(task), "--out", str(run), "--seed", "9"]).exit_code == 9
    told = runner.invoke(app, ["tell", str(run), str(execute_kinematically(reference))])
    assert told.exit_code == 0, told.stderr
    assert float(told.stdout) == pytest.approx(json.loads((run / "summary.json").read_text())["initial_robustness"], rel=1e-9)
    for number in (1, 2):
        reference = Path(runner.invoke(app, ["ask", str(run)]).stdout.strip())
        told = runner.invoke(app, ["tell", str(run), str(execute_kinematically(reference)), "--json"])
        record = json.loads(told.stdout)
        assert record["trial"] == number and record["budget"] == 2 and record["satisfied"] == (record["robustness"] > 0)
    done = runner.invoke(app, ["ask", str(run)])
    assert done.exit_code == 0 and done.stdout == "" and "the run has all its trials" in done.stderr
    both = runner.invoke(app, ["tell", str(run)])
    assert both.exit_code == 2 and "give the signals CSV of the pending trial, --failed REASON or --abandon" in both.stderr


@pytest.mark.slow
@pytest.mark.heavy
def test_a_shell_script_loop_with_the_pybullet_executor_matches_optimize_and_survives_a_kill(tmp_path):
    """The acceptance of ask/tell: a shell loop, killed between ask and tell and started again."""
    stlopt = str(Path(sys.executable).parent / "stlopt")
    script = tmp_path / "loop.sh"
    script.write_text(
        "set -e\n"
        'while ref=$("$STLOPT" ask "$TASK" --out "$RUN" -N 4 -M 2); [ -n "$ref" ]; do\n'
        '  [ -n "$STOP_AT" ] && [ "$ref" != "${ref%$STOP_AT/reference.csv}" ] && exit 3\n'
        '  "$PYTHON" "$EXECUTOR" "$ref" "$(dirname "$ref")/signals.csv"\n'
        '  "$STLOPT" tell "$RUN" "$(dirname "$ref")/signals.csv" > /dev/null\n'
        "done\n"
    )
    environment = dict(
        os.environ, STLOPT=stlopt, TASK=str(ROOT / "configs" / "phi1.yaml"), RUN=str(tmp_path / "asked"), PYTHON=sys.executable,
        EXECUTOR=str(ROOT / "examples" / "pybullet_executor.py"), STOP_AT="trial-0002",
    )  # fmt: skip
    stopped = subprocess.run(["bash", str(script)], env=environment, capture_output=True, text=True, cwd=ROOT)
    assert stopped.returncode == 3, stopped.stderr
    environment["STOP_AT"] = ""
    finished = subprocess.run(["bash", str(script)], env=environment, capture_output=True, text=True, cwd=ROOT)
    assert finished.returncode == 0, finished.stderr
    optimized = subprocess.run(
        [stlopt, "optimize", str(ROOT / "configs" / "phi1.yaml"), "--out", str(tmp_path / "optimized"), "-N", "4", "-M", "2", "--backend", "pybullet"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert optimized.returncode == 0, optimized.stderr
    assert recorded(tmp_path / "asked") == recorded(tmp_path / "optimized")


def _rewritten(path, target, change):
    """A copy of the signal CSV at `path` with `change(column name, values)` applied."""
    from stl_lfd.signals import read_signal_csv

    signals = read_signal_csv(path)
    columns = {name: change(name, np.array(values, dtype=float)) for name, values in signals.columns.items()}
    times = change("t", np.array(signals.times, dtype=float))
    write_signal_csv(type(signals)(times, columns, str(target)), target, digits=17)
    return target


def test_absurd_signals_are_refused_and_the_next_ask_is_what_it_would_have_been(tmp_path, learned_model_file):
    from stl_lfd.sim.plausibility import ImplausibleSignals

    proposals = {}
    for name, absurd in (("plain", False), ("poisoned", True)):
        folder = tmp_path / name
        folder.mkdir()
        _, first = start(folder, learned_model_file)
        run = folder / "asked"
        tell(run, execute_kinematically(first.reference))
        for _ in range(2):  # the initial design, then trial 3 from the GP
            asked = ask(run)
            signals = execute_kinematically(asked.reference)
            if absurd and asked.trial == 2:
                cases = {
                    "everywhere 1e300": lambda column, values: np.full_like(values, 1e300) if column in "xyz" else values,
                    "one sample at 1e308": lambda column, values: np.where(np.arange(values.size) == 9, 1e308, values) if column == "x" else values,
                    "milliseconds": lambda column, values: values * 1000 if column == "t" else values,
                    "a metre off": lambda column, values: values + 1.0 if column == "x" else values,
                    "a crushing force": lambda column, values: values + 1e5 if column == "force" else values,
                }
                for label, change in cases.items():
                    bad = _rewritten(signals, tmp_path / f"{label}.csv", change)
                    with pytest.raises(ImplausibleSignals, match=r"\.csv"):
                        tell(run, bad)
                    assert [entry.trial for entry in RunDirectory.open(run).pending()] == [2], label
            tell(run, signals)
        proposals[name] = (ask(run).trial, read_reference_csv(ask(run).reference).positions.tolist(), recorded(run))
    assert proposals["poisoned"] == proposals["plain"]


def test_ask_with_more_iterations_extends_the_budget_that_tell_counts(tmp_path, learned_model_file):
    _, first = start(tmp_path, learned_model_file, trials=3)
    run = tmp_path / "asked"
    tell(run, execute_kinematically(first.reference))
    loop(run)
    asked = runner.invoke(app, ["ask", str(run), "-N", "5"])
    assert asked.exit_code == 0, asked.stderr
    told = runner.invoke(app, ["tell", str(run), str(execute_kinematically(Path(asked.stdout.strip())))])
    assert told.exit_code == 0, told.stderr
    assert f"1 trial left: stlopt ask {run}" in told.stderr
    assert json.loads((run / "summary.json").read_text())["budget"] == 5


def test_a_run_executed_in_two_ways_says_so():
    from stl_lfd.optim.runs.recorder import combined_execution

    assert combined_execution("pybullet", "pybullet") == "pybullet"
    assert combined_execution("", "kinematic") == "kinematic"  # a run recorded before executed_by
    assert combined_execution("pybullet", "stlopt ask/tell") == "pybullet, then stlopt ask/tell"
    assert combined_execution("pybullet, then stlopt ask/tell", "stlopt ask/tell") == "pybullet, then stlopt ask/tell"
