"""Sweeps: grids of runs, local workers or Ray, finished cells skipped."""

import csv
import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.errors import ConfigError, RunError
from stl_lfd.optim.runs.sweep import aggregate, local_results, read_table, run_sweep
from stl_lfd.optim.runs.sweep_file import load_sweep, merged

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()
COMPARED = (
    "cell",
    "task",
    "variant",
    "method",
    "seed",
    "satisfied",
    "first_satisfied_trial",
    "best_robustness",
    "initial_robustness",
    "trials",
    "failed_trials",
)


def task_file(folder, model_file):
    path = folder / "small.yaml"
    path.write_text(
        f"name: small\nspec: {ROOT / 'specs' / 'phi1.stl'}\nmodel: {model_file}\nbackend: kinematic\nduration: 22\nrate: 50\n"
        "parameters:\n  means: {components: [2, 3]}\n  durations: {components: all}\noptimizer: {initial: 2, trials: 4}\n"
    )
    return path


def sweep_file(folder, model_file, extra="", seeds=2):
    task_file(folder, model_file)
    path = folder / "sweep.yaml"
    path.write_text(f"name: grid\ntasks: [small.yaml]\nmethods: [stl, random]\nseeds: {seeds}\n" + extra)
    return path


def compared(folder):
    return [{key: row[key] for key in COMPARED} for row in read_table(folder)]


@pytest.mark.slow
def test_a_sweep_runs_every_cell_as_a_run_directory_and_skips_finished_ones(tmp_path, learned_model_file):
    plan = load_sweep(sweep_file(tmp_path, learned_model_file))
    assert [cell.name for cell in plan.cells] == ["small-stl-seed0", "small-stl-seed1", "small-random-seed0", "small-random-seed1"]
    calls = []

    def in_process(cells):
        from stl_lfd.optim.runs.sweep import run_cell

        for cell in cells:
            calls.append(cell.name)
            yield run_cell(cell)

    records = run_sweep(plan, tmp_path / "out", in_process)
    assert len(records) == 4 and calls == [cell.name for cell in plan.cells]
    for cell in plan.cells:
        run = tmp_path / "out" / "runs" / cell.name
        assert json.loads((run / "summary.json").read_text())["trials"] == 4 and not (run / ".lock").exists()
        assert json.loads((run / "summary.json").read_text())["seed"] == cell.seed
    assert [row["cell"] for row in read_table(tmp_path / "out")] == calls
    calls.clear()
    again = run_sweep(plan, tmp_path / "out", in_process)
    assert calls == [] and again == records
    groups = aggregate(records)
    assert [(group.method, group.runs) for group in groups] == [("stl", 2), ("random", 2)]
    assert groups[0].satisfied == sum(1 for record in records[:2] if record["satisfied"])


@pytest.mark.slow
def test_a_killed_sweep_finishes_only_the_missing_cells(tmp_path, learned_model_file):
    plan = load_sweep(sweep_file(tmp_path, learned_model_file))

    def killed_after_two(cells):
        from stl_lfd.optim.runs.sweep import run_cell

        for index, cell in enumerate(cells):
            if index == 2:
                raise KeyboardInterrupt
            yield run_cell(cell)

    with pytest.raises(KeyboardInterrupt):
        run_sweep(plan, tmp_path / "out", killed_after_two)
    assert len(read_table(tmp_path / "out")) == 2
    before = {path: path.stat().st_mtime_ns for path in (tmp_path / "out" / "runs").rglob("trials.jsonl")}
    ran = []

    def recording(cells):
        from stl_lfd.optim.runs.sweep import run_cell

        for cell in cells:
            ran.append(cell.name)
            yield run_cell(cell)

    run_sweep(plan, tmp_path / "out", recording)
    assert ran == ["small-random-seed0", "small-random-seed1"]
    assert all(path.stat().st_mtime_ns == mtime for path, mtime in before.items())


def test_variants_change_task_keys_and_bad_sweeps_are_refused(tmp_path, learned_model_file):
    path = sweep_file(tmp_path, learned_model_file, "variants:\n  narrow: {parameters: {means: {beta: 0.5}}}\n  classic: {semantics: classic}\n")
    plan = load_sweep(path)
    assert len(plan.cells) == 8
    narrow = next(cell for cell in plan.cells if cell.variant == "narrow")
    assert narrow.name == "small-narrow-stl-seed0" and narrow.task.parameters["skill"].means.beta == 0.5
    assert narrow.task.parameters["skill"].means.components == (2, 3)  # merged, not replaced
    assert next(cell for cell in plan.cells if cell.variant == "classic").task.semantics == "classic"
    assert merged({"a": {"b": 1, "c": 2}, "d": 3}, {"a": {"b": 5}}) == {"a": {"b": 5, "c": 2}, "d": 3}
    for text, message in [
        ("tasks: []\n", "'tasks' must be a non-empty list"),
        ("tasks: [nope.yaml]\n", "'tasks' names nope.yaml, which does not exist"),
        ("tasks: [small.yaml]\nmethods: [magic]\n", "'methods' must be a list of stl, plan, pi, logei, random"),
        ("tasks: [small.yaml]\nseeds: -1\n", "'seeds' must be at least 1"),
        ("tasks: [small.yaml]\nbackend: gazebo\n", "'backend' must be one of"),
        ("tasks: [small.yaml]\ncolour: red\n", "unknown key 'colour'"),
        ("tasks: [small.yaml]\nvariants:\n  bad: {parameters: {means: {beta: -1}}}\n", "(variant bad of bad.yaml)"),
        ("tasks: [small.yaml, small.yaml]\n", "two cells are both called small-plan-seed0"),
    ]:
        bad = tmp_path / "bad.yaml"
        bad.write_text(text)
        with pytest.raises(ConfigError, match=__import__("re").escape(message)):
            load_sweep(bad)


@pytest.mark.slow
def test_a_sweep_folder_holding_another_run_is_refused(tmp_path, learned_model_file):
    plan = load_sweep(sweep_file(tmp_path, learned_model_file, "trials: 2\n"))
    from stl_lfd.optim.runs.sweep import run_cell

    run_sweep(plan, tmp_path / "out", lambda cells: (run_cell(cell) for cell in cells))
    (tmp_path / "sweep.yaml").write_text((tmp_path / "sweep.yaml").read_text().replace("trials: 2", "trials: 3\ninitial: 1"))
    with pytest.raises(RunError, match="holds another run than the sweep's cell small-stl-seed0"):
        run_sweep(load_sweep(tmp_path / "sweep.yaml"), tmp_path / "out", lambda cells: iter(()))


@pytest.mark.slow
@pytest.mark.heavy
def test_the_command_prints_the_table_and_writes_the_figure_with_local_workers(tmp_path, learned_model_file):
    path = sweep_file(tmp_path, learned_model_file)
    result = runner.invoke(app, ["sweep", str(path), "--out", str(tmp_path / "out"), "--jobs", "2"])
    assert result.exit_code == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[:4] == ["task", "variant", "method", "satisfied"]
    assert [line.split()[2] for line in lines[1:]] == ["stl", "random"]
    assert (tmp_path / "out" / "sweep.png").stat().st_size > 1000
    report = runner.invoke(app, ["report", str(tmp_path / "out")])
    assert report.exit_code == 0 and report.stdout == result.stdout


@pytest.mark.slow
@pytest.mark.heavy
@pytest.mark.xdist_group("ray")  # one Ray at a time on the machine (tests/optim/test_ray_trials.py)
def test_ray_gives_the_table_of_local_workers(tmp_path, learned_model_file):
    import ray

    from stl_lfd.optim.runs.sweep import ray_results

    plan = load_sweep(sweep_file(tmp_path, learned_model_file, seeds=1))  # a cell for each of ray's two workers
    run_sweep(plan, tmp_path / "local", lambda cells: local_results(cells, 2))
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)  # a new Ray, not a cluster running here
    try:
        run_sweep(plan, tmp_path / "ray", lambda cells: ray_results(cells, None))
    finally:
        ray.shutdown()
    assert compared(tmp_path / "ray") == compared(tmp_path / "local")


@pytest.mark.slow
@pytest.mark.heavy
def test_ctrl_c_stops_a_sweep_and_the_rerun_does_the_rest(tmp_path, learned_model_file):
    from tests.processes import deliverable_sigint, interrupt, wait_for

    path = sweep_file(tmp_path, learned_model_file, "trials: 6\n")
    stlopt = str(Path(sys.executable).parent / "stlopt")
    command = [stlopt, "sweep", str(path), "--out", str(tmp_path / "out"), "--jobs", "1"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=deliverable_sigint)
    table = tmp_path / "out" / "sweep.csv"
    wait_for(lambda: table.exists() and len(table.read_text().splitlines()) >= 2, timeout=300)
    _, err = interrupt(process)
    assert process.returncode == -signal.SIGINT, err
    assert "Continue with: stlopt sweep" in err and "Traceback" not in err
    names = [cell.name for cell in load_sweep(path).cells]
    done = [row["cell"] for row in read_table(tmp_path / "out")]
    # one worker runs the cells in order: the finished ones are a prefix, each a complete run
    # directory, and the cell in flight left nothing behind
    assert done == names[: len(done)] and len(done) < len(names)
    assert sorted(folder.name for folder in (tmp_path / "out" / "runs").iterdir()) == sorted(done)
    assert not any((tmp_path / "out" / ".scratch").glob("*"))
    kept = {name: (tmp_path / "out" / "runs" / name / "trials.jsonl").stat().st_mtime_ns for name in done}
    finished = subprocess.run(command, capture_output=True, text=True)
    assert finished.returncode == 0, finished.stderr
    assert f"{len(done)} of 4 cells already done" in finished.stderr
    ran = [line.split(":")[0] for line in finished.stderr.splitlines() if line.startswith(tuple(names))]
    assert ran == names[len(done) :]  # only the missing cells ran again
    assert all((tmp_path / "out" / "runs" / name / "trials.jsonl").stat().st_mtime_ns == mtime for name, mtime in kept.items())
    assert len(read_table(tmp_path / "out")) == 4
    with open(table) as stream:
        assert [row["cell"] for row in csv.DictReader(stream)] == [cell.name for cell in load_sweep(path).cells]
