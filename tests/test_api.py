"""The public Python API: the examples of the Python API page (docs/api.md) run, `optimize`
from objects reproduces the command line's trials, and settings are checked when objects are made."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

import stl_lfd
from stl_lfd.cli import app
from stl_lfd.errors import ConfigError, ModelError, RunError
from tests.conftest import ROOT
from tests.optim.test_run import small_task


def api_page_python_blocks() -> list[str]:
    """The Python examples of the documentation's Python API page, in order."""
    return re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), flags=re.S)


@pytest.mark.slow
def test_the_api_page_python_examples_run(monkeypatch, capsys):
    blocks = api_page_python_blocks()
    assert len(blocks) == 5
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "docs/api.md", "exec"), namespace)
    printed = capsys.readouterr().out.splitlines()
    assert float(printed[1]) == pytest.approx(-0.31)
    assert namespace["result"].best_robustness >= namespace["result"].initial_robustness
    assert len(namespace["result"].history) == 6
    assert namespace["insert"].frame_names_ == ["base", "shaft", "holder"]
    end = namespace["holder"].from_base(namespace["moved"].positions[-1:])[0]
    assert abs(end[0] - 0.008) < 0.004 and abs(end[1]) < 0.004  # the demonstrated stop, carried to the moved holder
    for block in blocks:  # every `# prints X` comment is what its line prints
        for shown in re.findall(r"# prints (.+)", block):
            assert shown.strip() in printed, f"docs/api.md says it prints {shown.strip()!r}; it printed {printed}"


def test_import_stl_lfd_is_lazy():
    code = "import sys, stl_lfd; stl_lfd.Spec; print(any(m in sys.modules for m in ('torch', 'pybullet', 'botorch')))"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
    assert set(stl_lfd.__all__) <= set(dir(stl_lfd))
    with pytest.raises(AttributeError):
        stl_lfd.nothing_here  # noqa: B018 (the attribute access is the test)


@pytest.mark.slow
def test_optimize_from_objects_reproduces_the_command_lines_trials(tmp_path, learned_model, learned_model_file):
    task = small_task(tmp_path, learned_model_file)  # kinematic, 50 Hz, 22 s, means of 2-3 and all durations, 3 + 2 trials, seed 2
    assert CliRunner().invoke(app, ["optimize", str(task), "--out", str(tmp_path / "run")]).exit_code == 0
    recorded = [json.loads(line) for line in (tmp_path / "run" / "trials.jsonl").read_text().splitlines()]
    # No file: the spec as text (phi1 with its regions written out), the model as an object.
    regions = (ROOT / "specs" / "regions.stl").read_text()
    phi1 = "\n".join(line for line in (ROOT / "specs" / "phi1.stl").read_text().splitlines() if not line.startswith("include"))
    result = stl_lfd.optimize(
        learned_model,
        stl_lfd.Spec.parse(regions + "\n" + phi1),
        stl_lfd.Parameters(means=stl_lfd.MeanParameters(components=(2, 3)), durations=stl_lfd.DurationParameters(components="all")),
        stl_lfd.Optimizer("stl", initial=3, trials=5, seed=2),
        duration=22,
        rate=50,
        backend="kinematic",
    )
    assert [trial.robustness for trial in result.history] == [line["robustness"] for line in recorded]
    assert all(np.array_equal(trial.x, line["x"]) for trial, line in zip(result.history, recorded))
    assert result.best_robustness == max(line["robustness"] for line in recorded)
    assert result.best_model.n_states == learned_model.n_states


@pytest.mark.slow
def test_optimize_with_a_run_directory_records_a_run_the_command_line_continues(tmp_path, learned_model, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    assert CliRunner().invoke(app, ["optimize", str(task), "--out", str(tmp_path / "cli"), "-N", "6"]).exit_code == 0
    run = tmp_path / "python"
    settings = dict(duration=22, rate=50, backend="kinematic", out=run)
    parameters = stl_lfd.Parameters(means=stl_lfd.MeanParameters(components=(2, 3)), durations=stl_lfd.DurationParameters(components="all"))
    result = stl_lfd.optimize(learned_model, ROOT / "specs" / "phi1.stl", parameters, stl_lfd.Optimizer("stl", initial=3, trials=5, seed=2), **settings)
    assert stl_lfd.Spec.load(run / "spec.stl").tree == stl_lfd.Spec.load(ROOT / "specs" / "phi1.stl").tree
    on_disk = [json.loads(line)["robustness"] for line in (run / "trials.jsonl").read_text().splitlines()]
    assert on_disk == [trial.robustness for trial in result.history]
    assert sorted(result.signals) == [0, 1, 2, 3, 4, 5] and (run / "signals" / "trial-0005.csv").is_file()
    # The command line continues the Python run to 6 trials, as it continues its own.
    resumed = CliRunner().invoke(app, ["optimize", str(run / "task.yaml"), "--out", str(run), "--resume", "-N", "6"])
    assert resumed.exit_code == 0, resumed.output
    cli = [json.loads(line) for line in (tmp_path / "cli" / "trials.jsonl").read_text().splitlines()]
    python = [json.loads(line) for line in (run / "trials.jsonl").read_text().splitlines()]
    assert [line["robustness"] for line in python] == [line["robustness"] for line in cli]
    assert json.loads((run / "summary.json").read_text())["trials"] == 6
    with pytest.raises(RunError, match="exists"):
        stl_lfd.optimize(learned_model, ROOT / "specs" / "phi1.stl", parameters, **settings)


def test_settings_are_checked_when_objects_are_made():
    with pytest.raises(ConfigError, match="exceeds"):
        stl_lfd.Optimizer(initial=10, trials=5)
    with pytest.raises(ConfigError, match="method"):
        stl_lfd.Optimizer(method="magic")
    with pytest.raises(ConfigError, match="seed"):
        stl_lfd.Optimizer(seed=-1)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: stl_lfd.MeanParameters(components=(2, 2)), "lists a state twice"),
        (lambda: stl_lfd.MeanParameters(components=(0,)), "state numbers from 1"),
        (lambda: stl_lfd.MeanParameters(components=(2,), coordinates=("w",)), "may hold x, y, z"),
        (lambda: stl_lfd.MeanParameters(components=(2,), beta=0), "'means.beta' must be positive"),
        (lambda: stl_lfd.DurationParameters(components="all", width=-1), "'durations.width' must be positive"),
        (lambda: stl_lfd.Parameters(transitions="diag"), "'transitions' must be one of none, band, full"),
        (lambda: stl_lfd.Parameters(), "select nothing to optimise"),
    ],
)
def test_parameters_are_checked_when_made(make, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        make()


@pytest.mark.slow
def test_learning_from_tables_in_memory_equals_learning_from_the_folder():
    folder = ROOT / "demos" / "three_regions"
    tables = [stl_lfd.read_signal_csv(path) for path in sorted(folder.glob("*.csv"))]
    in_memory, _ = stl_lfd.learn(tables, 6)
    from_folder, _ = stl_lfd.learn_from_folder(folder, 6)
    assert np.array_equal(in_memory.means_, from_folder.means_) and np.array_equal(in_memory.transmat_, from_folder.transmat_)
    with pytest.raises(ModelError, match="no demonstrations"):
        stl_lfd.learn([], 6)
