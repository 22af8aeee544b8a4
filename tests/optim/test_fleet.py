"""A fleet of robots on one run: `stlopt ask --robot` hands out up to `workers` trials at once,
`tell --trial` records them in any order, and the run is the one `optimize --workers` makes."""

import json

import pytest

from stl_lfd.errors import RunError, WaitError
from stl_lfd.optim import finish_run, load_task, start_run
from stl_lfd.optim.inputs import resolve
from stl_lfd.optim.runs.asktell import ABANDONED, ask, ask_new, tell
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.runs.resume import inputs_record
from stl_lfd.optim.task import Overrides
from tests.optim.test_asktell import execute_kinematically, recorded, task_file


def fleet_task(tmp_path, model_file, trials=6):
    """A run asked for as `stlopt ask TASK --workers 2` does (kinematic, method stl, 2 initial
    trials, seed 4), its unoptimised skill told."""
    tmp_path.mkdir(exist_ok=True)
    file_task = load_task(task_file(tmp_path, model_file, trials=trials))
    given = Overrides(workers=2)
    task, run = given.applied_to(file_task), tmp_path / "asked"
    first = ask_new(resolve(task), run, inputs_record(file_task, given, resolve(task)))
    tell(run, execute_kinematically(first.reference))
    return task, run


def two_robots(run, reverse: bool) -> None:
    """Robots a and b each take a trial, execute it, and tell it (b first when `reverse`)."""
    while True:
        asked = [ask(run, robot=robot) for robot in ("a", "b")]
        asked = [item for item in asked if item is not None]
        if not asked:
            return
        signals = [(item.trial, execute_kinematically(item.reference)) for item in asked]
        for number, path in reversed(signals) if reverse else signals:
            tell(run, path, trial=number)


@pytest.mark.slow
def test_told_in_reverse_the_run_is_the_run_told_in_order_and_optimize_with_two_workers(tmp_path, learned_model_file):
    task, forward = fleet_task(tmp_path / "forward", learned_model_file)
    two_robots(forward, reverse=False)
    _, backward = fleet_task(tmp_path / "backward", learned_model_file)
    two_robots(backward, reverse=True)
    assert len(recorded(forward)) == 6 and recorded(backward) == recorded(forward)
    finish_run(start_run(task, tmp_path / "optimized"))
    assert recorded(tmp_path / "optimized") == recorded(forward)


def test_a_third_robot_waits_and_a_trial_told_early_is_recorded_after_those_before_it(tmp_path, learned_model_file):
    _, run = fleet_task(tmp_path, learned_model_file)
    first, second = ask(run, robot="a"), ask(run, robot="b")
    assert (first.trial, second.trial) == (1, 2) and ask(run, robot="a").again
    with pytest.raises(WaitError, match=r"trial 1 to robot a, trial 2 to robot b \(the task's optimizer.workers lets 2 trials be handed out at once\)"):
        ask(run, robot="c")
    early = tell(run, execute_kinematically(second.reference), trial=2)
    assert not early.recorded and early.robustness is not None and recorded(run) == []
    assert [entry.trial for entry in RunDirectory.open(run).pending() if entry.told is not None] == [2]
    with pytest.raises(RunError, match="trial 2 is not waiting to be told"):
        tell(run, execute_kinematically(second.reference), trial=2)
    late = tell(run, execute_kinematically(first.reference))  # the only one left: no --trial needed
    assert late.recorded and [trial["trial"] for trial in map(json.loads, (run / "trials.jsonl").read_text().splitlines())] == [1, 2]
    assert not (run / "pending.json").exists()


def test_an_abandoned_trial_is_recorded_as_failed_and_the_run_goes_on(tmp_path, learned_model_file):
    _, run = fleet_task(tmp_path, learned_model_file)
    first, second = ask(run, robot="a"), ask(run, robot="b")
    tell(run, execute_kinematically(second.reference), trial=2)
    with pytest.raises(RunError, match="several trials are handed out|trial 9 is not waiting"):
        tell(run, None, ABANDONED, trial=9)
    abandoned = tell(run, None, ABANDONED, trial=first.trial)
    assert abandoned.trial.status == "failed" and abandoned.trial.error == "execution failed: abandoned: never told"
    assert [(trial[2], trial[3]) for trial in recorded(run)] == [("failed", "execution failed: abandoned: never told"), ("ok", None)]
    following = ask(run, robot="a")
    assert following.trial == 3 and not following.again


def test_a_trial_waits_for_the_trials_its_batch_learns_from(tmp_path, learned_model_file):
    _, run = fleet_task(tmp_path, learned_model_file)
    slow = ask(run, robot="slow")
    for expected in (2, 3, 4):  # robot fast executes trial after trial while robot slow holds trial 1
        fast = ask(run, robot="fast")
        assert fast.trial == expected
        tell(run, execute_kinematically(fast.reference), trial=fast.trial)
    with pytest.raises(WaitError, match=r"trial 5 is chosen from trials 1 to 2; tell trial 1 to robot slow first"):
        ask(run, robot="fast")
    tell(run, execute_kinematically(slow.reference), trial=1)
    assert len(recorded(run)) == 4 and ask(run, robot="fast").trial == 5


def test_the_commands_of_a_fleet(tmp_path, learned_model_file):
    from typer.testing import CliRunner

    from stl_lfd.cli import app

    runner, run = CliRunner(), tmp_path / "lab"
    task = task_file(tmp_path, learned_model_file)
    first = runner.invoke(app, ["ask", str(task), "--out", str(run), "--workers", "2"])
    assert first.exit_code == 0, first.stderr
    assert runner.invoke(app, ["tell", str(run), str(execute_kinematically(first.stdout.strip()))]).exit_code == 0
    handed = {robot: runner.invoke(app, ["ask", str(run), "--robot", robot]) for robot in ("a", "b")}
    assert all(result.exit_code == 0 for result in handed.values()) and "trial 1 (" in handed["a"].stderr
    assert "to execute on robot b; then: stlopt tell" in handed["b"].stderr and handed["b"].stderr.rstrip().endswith("--trial 2")
    early = runner.invoke(app, ["tell", str(run), str(execute_kinematically(handed["b"].stdout.strip())), "--trial", "2"])
    assert early.exit_code == 0 and "trial 2 is recorded once trial 1 to robot a is told" in early.stderr
    assert "3 trials left" in early.stderr  # of 5: trials 1 and 2 are out
    busy = runner.invoke(app, ["ask", str(run), "--robot", "c"])
    assert busy.exit_code == 0 and busy.stdout.strip().endswith("trial-0003/reference.csv")  # trial 2 is told: a place is free
    full = runner.invoke(app, ["ask", str(run), "--robot", "d"])
    assert full.exit_code == 10 and full.stdout == "" and "trial 1 to robot a, trial 3 to robot c" in full.stderr
    gone = runner.invoke(app, ["tell", str(run), "--trial", "1", "--abandon"])
    assert gone.exit_code == 0 and "trial 1 failed: execution failed: abandoned: never told" in gone.stderr
    assert [trial[2] for trial in recorded(run)] == ["failed", "ok"]
    for number in (4, 5):  # robot a takes the last two trials of 5 and tells them while trial 3 is out
        taken = runner.invoke(app, ["ask", str(run), "--robot", "a"])
        assert taken.stdout.strip().endswith(f"trial-000{number}/reference.csv"), taken.stderr
        assert runner.invoke(app, ["tell", str(run), str(execute_kinematically(taken.stdout.strip())), "--trial", str(number)]).exit_code == 0
    last = runner.invoke(app, ["ask", str(run), "--robot", "e"])
    assert last.exit_code == 0 and last.stdout == "" and "every trial is handed out; the run is complete once trial 3 to robot c is told" in last.stderr


def test_a_run_asked_for_before_fleets_keeps_its_pending_trial(tmp_path, learned_model_file):
    _, run = fleet_task(tmp_path, learned_model_file)
    asked = ask(run)
    single = json.loads((run / "pending.json").read_text())["pending"][0]
    del single["robot"]
    (run / "pending.json").write_text(json.dumps(single))  # pending.json as runs wrote it before
    again = ask(run)
    assert (again.trial, again.again) == (asked.trial, True)
    assert tell(run, execute_kinematically(asked.reference)).recorded and len(recorded(run)) == 1
