"""Resuming runs: the same command plus --resume works, real changes are refused, one writer
at a time, Ctrl-C kills by SIGINT, and run folders are ordinary folders."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from tests.conftest import ROOT
from tests.optim.test_run import small_task
from tests.processes import deliverable_sigint, interrupt, wait_for

runner = CliRunner()
STLOPT = str(Path(sys.executable).parent / "stlopt")


@pytest.mark.slow
def test_the_same_command_plus_resume_works_for_every_option(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    options = [
        "--spec",
        str(ROOT / "specs" / "phi1.stl"),
        "-N",
        "3",
        "-M",
        "2",
        "--seed",
        "4",
        "--backend",
        "kinematic",
        "--method",
        "pi",
        "--out",
        str(tmp_path / "run"),
    ]
    first = runner.invoke(app, ["optimize", str(task)] + options)
    assert first.exit_code == 0, first.stderr
    summary = (tmp_path / "run" / "summary.json").read_bytes()
    again = runner.invoke(app, ["optimize", str(task)] + options + ["--resume"])
    assert again.exit_code == 0, again.stderr
    assert "the run is complete (3 trials" in again.stderr
    assert (tmp_path / "run" / "summary.json").read_bytes() == summary  # nothing ran, nothing changed
    longer = runner.invoke(app, ["optimize", str(task)] + options[:2] + ["-N", "4"] + options[4:] + ["--resume"])
    assert longer.exit_code == 0, longer.stderr
    assert json.loads(longer.stdout)["trials"] == 4
    bare = runner.invoke(app, ["optimize", str(task), "--out", str(tmp_path / "run"), "--resume"])
    assert bare.exit_code == 0 and json.loads(bare.stdout)["seed"] == 4


@pytest.mark.slow
def test_resume_refuses_a_spec_whose_meaning_changed_but_not_a_new_comment(tmp_path, learned_model_file):
    spec = tmp_path / "mine.stl"
    spec.write_text((ROOT / "specs" / "phi1.stl").read_text())
    (tmp_path / "regions.stl").write_text((ROOT / "specs" / "regions.stl").read_text())
    task = small_task(tmp_path, learned_model_file)
    task.write_text(task.read_text().replace(str(ROOT / "specs" / "phi1.stl"), str(spec)))
    out = ["--out", str(tmp_path / "run")]
    assert runner.invoke(app, ["optimize", str(task), "-N", "3", *out]).exit_code == 0
    spec.write_text("# a comment\n" + spec.read_text())
    assert runner.invoke(app, ["optimize", str(task), "-N", "4", *out, "--resume"]).exit_code == 0
    spec.write_text(spec.read_text().replace("G[12, 17]", "G[12, 16]"))
    changed = runner.invoke(app, ["optimize", str(task), "-N", "5", *out, "--resume"])
    assert changed.exit_code == 9 and "the spec changed since the run started" in changed.stderr
    assert len((tmp_path / "run" / "trials.jsonl").read_text().splitlines()) == 4


@pytest.mark.slow
def test_a_behaviour_run_started_from_a_relative_task_path_resumes(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # configs/phi3_strict.yaml, as a user in the repository types it
    options = ["--backend", "kinematic", "-M", "2", "--out", str(tmp_path / "run")]
    assert runner.invoke(app, ["optimize", "configs/phi3_strict.yaml", "-N", "2", *options]).exit_code == 0
    resumed = runner.invoke(app, ["optimize", "configs/phi3_strict.yaml", "-N", "3", *options, "--resume"])
    assert resumed.exit_code == 0, resumed.stderr
    assert json.loads(resumed.stdout)["trials"] == 3


def test_a_run_folder_honours_the_umask(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    previous = os.umask(0o022)
    try:
        assert runner.invoke(app, ["optimize", str(task), "-N", "2", "-M", "2", "--out", str(tmp_path / "run")]).exit_code == 0
    finally:
        os.umask(previous)
    assert (tmp_path / "run").stat().st_mode & 0o777 == 0o755
    assert (tmp_path / "run" / "summary.json").stat().st_mode & 0o777 == 0o644


@pytest.mark.slow
@pytest.mark.heavy
def test_two_concurrent_resumes_one_proceeds_one_refuses(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    run = tmp_path / "run"
    command = [STLOPT, "optimize", str(task), "--out", str(run), "-N", "12", "-M", "8"]  # long enough to overlap the second
    assert subprocess.run(command[:-4] + ["-N", "2", "-M", "2"], capture_output=True).returncode == 0
    # The run was started with -M 2; resuming with another -M is a change and is refused, so
    # both resumes give the run's own -M.
    command = command[:-2] + ["-M", "2", "--resume"]
    first = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for(lambda: (run / ".lock").read_text().strip() == str(first.pid))
    second = subprocess.run(command, capture_output=True, text=True, timeout=600)
    out, err = first.communicate(timeout=600)
    assert first.returncode == 0, err
    assert second.returncode == 11  # busy: try again, unlike a damaged run (9)
    assert second.stderr.strip() == f"error: {run}: the run is being written by another stlopt process (PID {first.pid}); wait for it to end or stop it"
    numbers = [json.loads(line)["trial"] for line in (run / "trials.jsonl").read_text().splitlines()]
    assert numbers == list(range(1, 13))


@pytest.mark.slow
def test_ctrl_c_keeps_the_trials_and_dies_by_sigint(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    run = tmp_path / "run"
    process = subprocess.Popen(
        [STLOPT, "optimize", str(task), "--out", str(run), "-N", "500"],  # far more than the test waits for
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=deliverable_sigint,
    )
    wait_for(lambda: (run / "trials.jsonl").exists() and len((run / "trials.jsonl").read_text().splitlines()) >= 3)
    out, err = interrupt(process)
    assert process.returncode == -signal.SIGINT
    assert f"Continue with: stlopt optimize {task} --out {run} --resume" in err
    kept = len((run / "trials.jsonl").read_text().splitlines())
    assert kept >= 3 and "Traceback" not in err


def test_staging_folders_of_killed_runs_are_removed_by_the_next_run(tmp_path):
    import time

    from stl_lfd.optim.runs.lock import RunLock
    from stl_lfd.optim.runs.staging import ABANDONED_AFTER, remove_abandoned

    long_ago = time.time() - 2 * ABANDONED_AFTER
    abandoned, building, fresh = (tmp_path / f".run.{name}" for name in ("k1ll3d_a", "bu1ld_ab", "n3w_abcd"))
    users = tmp_path / ".run.backup"  # a hidden folder of the user's, with a lock file even
    for folder in (abandoned, building, fresh, users):
        folder.mkdir()
        (folder / ".lock").write_text("123\n")
    held = RunLock.acquire(building, building)  # another process building its run
    for folder in (abandoned, building, users):
        os.utime(folder, (long_ago, long_ago))
    remove_abandoned(tmp_path / "run")
    held.release()
    assert not abandoned.exists() and building.exists() and fresh.exists() and users.exists()


def test_a_run_recorded_with_the_older_spelling_of_pis_margin_resumes(tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    out = ["--backend", "kinematic", "--out", str(tmp_path / "run")]
    assert runner.invoke(app, ["optimize", str(task), "-N", "2", "-M", "1", *out]).exit_code == 0
    inputs = tmp_path / "run" / "inputs.json"
    recorded = json.loads(inputs.read_text())
    recorded["task"]["optimizer"]["xi"] = 0.1  # as runs recorded it before methods had their own settings
    inputs.write_text(json.dumps(recorded))
    assert runner.invoke(app, ["optimize", str(task), "-N", "3", "-M", "1", *out, "--resume"]).exit_code == 0
    recorded["task"]["optimizer"]["xi"] = 0.3
    inputs.write_text(json.dumps(recorded))
    refused = runner.invoke(app, ["optimize", str(task), "-N", "4", "-M", "1", *out, "--resume"])
    assert refused.exit_code == 9 and "'optimizer.pi' is absent here, {'xi': 0.3} in the run's" in refused.stderr
