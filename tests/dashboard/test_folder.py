"""What the dashboard reads of a folder of runs: runs and sweeps found, a run read as it grows,
damaged runs named as such."""

import json
import shutil
import time

from stl_lfd.dashboard.folder import RunView, find, sweep_runs
from stl_lfd.optim.runs.lock import RunLock


def test_the_folder_lists_its_runs_and_sweeps(runs_folder):
    listing = find(runs_folder)
    assert [path.name for path in listing.runs] == ["damaged", "finished"]
    assert [path.name for path in listing.sweeps] == ["grid"]
    assert [path.name for path in sweep_runs(listing.sweeps[0])] == ["small-random-seed0", "small-stl-seed0"]


def test_a_run_is_read_once_and_then_only_its_new_lines(runs_folder, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(runs_folder / "finished", run)
    lines = (run / "trials.jsonl").read_text().splitlines(keepends=True)
    (run / "trials.jsonl").write_text("".join(lines[:2]) + lines[2][:10])  # the third line half-written
    view = RunView(run)
    assert view.refresh() and list(view.trials.numbers) == [1, 2]
    assert not view.refresh()  # nothing changed: nothing read
    (run / "trials.jsonl").write_text("".join(lines))
    assert view.refresh() and list(view.trials.numbers) == list(range(1, len(lines) + 1))
    assert view.state() == "finished" and view.problem == ""
    best = max((json.loads(line) for line in lines), key=lambda record: record["robustness"])
    assert view.best() == (best["trial"], best["robustness"])


def test_damaged_and_half_written_runs_say_what_is_wrong(runs_folder, tmp_path):
    damaged = RunView(runs_folder / "damaged")
    damaged.refresh()
    assert damaged.state() == "damaged: trials.jsonl line 6: not a trial record"
    assert len(damaged.trials) == 5  # the trials before it are still shown
    run = tmp_path / "half"
    shutil.copytree(runs_folder / "finished", run)
    (run / "summary.json").write_text('{"budget": 5,')
    view = RunView(run)
    view.refresh()
    assert view.state() == "damaged: summary.json line 1: not JSON (Expecting property name enclosed in double quotes)"
    (run / "task.yaml").unlink()
    view = RunView(run)
    view.refresh()
    assert view.state().startswith("damaged: ") and "task.yaml" in view.state()


def test_a_run_being_written_and_one_waiting_for_tell(runs_folder, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(runs_folder / "finished", run)
    lock = RunLock.acquire(run, run)  # as stlopt writing the run holds it
    time.sleep(0.3)  # the kernel's list of locks is read at most every 0.2 s
    view = RunView(run)
    view.refresh()
    assert view.state() == "running"
    lock.release()
    time.sleep(0.3)  # the kernel's list of locks is read at most every 0.2 s
    (run / "pending.json").write_text(json.dumps({"pending": [{"trial": 6, "phase": "stl", "robot": "left", "asked": 0.0}]}))
    view.refresh()
    assert view.state() == "waiting for tell: trial 6 (left)"


def test_a_run_stopped_on_a_failed_trial_says_why(runs_folder, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(runs_folder / "finished", run)
    summary = json.loads((run / "summary.json").read_text()) | {"complete": False, "budget": 8}
    (run / "summary.json").write_text(json.dumps(summary))
    last = json.loads((run / "trials.jsonl").read_text().splitlines()[-1])
    with open(run / "trials.jsonl", "a") as stream:
        stream.write(json.dumps(last | {"trial": 6, "status": "failed", "robustness": None, "error": "ExecutionError: protective stop"}) + "\n")
    view = RunView(run)
    view.refresh()
    assert view.state() == "stopped after 6 of 8 trials; trial 6 failed: ExecutionError: protective stop"
