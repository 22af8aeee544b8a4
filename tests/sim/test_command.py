"""The command backend, the reference CSV and the safety gate (with a kinematic test executor)."""

import json
import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from stl_lfd.errors import ConfigError, ExecutionError, SignalError
from stl_lfd.optim import finish_run, load_task, start_run
from stl_lfd.rotations import DOWN, from_rotvec, multiply
from stl_lfd.sim import (
    Command,
    CommandBackend,
    Reference,
    Safety,
    UnsafeReference,
    check_reference,
    execute,
    load_scene,
    read_reference_csv,
    write_reference_csv,
)

ROOT = Path(__file__).resolve().parents[2]
FAKE = ROOT / "tests" / "executors" / "fake.py"
FORCE_SPEC = "L := x in [0.3, 0.7]\nphi := F L & G force < 5\n"


def executor_task(tmp_path, model_file, spec=None, trials=4, timeout=60, scene="free_space", backend="command"):
    spec_path = ROOT / "specs" / "phi1.stl"
    if spec is not None:
        spec_path = tmp_path / "spec.stl"
        spec_path.write_text(spec)
    path = tmp_path / "task.yaml"
    path.write_text(
        f"name: robot\nspec: {spec_path}\nmodel: {model_file}\nbackend: {backend}\nscene: {scene}\nduration: 22\nrate: 50\n"
        f"command:\n  run: [{sys.executable}, {FAKE}, '{{reference}}', '{{signals}}']\n  timeout: {timeout}\n"
        "parameters:\n  means: {components: [2, 3]}\n  durations: {components: all}\n"
        f"optimizer: {{initial: {min(2, trials)}, trials: {trials}, seed: 5}}\n"
    )
    return load_task(path)


def trials_of(run):
    return [json.loads(line) for line in (run / "trials.jsonl").read_text().splitlines()]


def sample_reference():
    times = np.arange(5) / 240
    positions = np.column_stack([0.4 + 0.01 * times, np.full(5, 0.1), 0.3 + np.sin(times)])
    skills = np.array(["pick", "pick", "grasp", "insert", "insert"])
    return Reference(times, positions, np.array([0.08, 0.08, 0.0, 0.0, 0.0]), ((times[2], "grasp"),), skills, np.array([1, 2, 0, 1, 1]))


def test_the_reference_csv_reads_back_exactly(tmp_path):
    reference = sample_reference()
    write_reference_csv(reference, tmp_path / "reference.csv", 0.08)
    assert (tmp_path / "reference.csv").read_text().splitlines()[0] == "t,x,y,z,gripper,skill,state,event,qx,qy,qz,qw"
    again = read_reference_csv(tmp_path / "reference.csv")
    assert np.array_equal(again.times, reference.times) and np.array_equal(again.positions, reference.positions)
    assert np.array_equal(again.gripper, reference.gripper) and again.events == reference.events
    assert list(again.skills) == list(reference.skills) and list(again.states) == [1, 2, 0, 1, 1]
    assert again.orientations is None  # straight down throughout, as written for a skill without orientation


def test_a_reference_with_orientations_reads_back_exactly_and_older_files_still_read(tmp_path):
    turning = from_rotvec(np.outer(np.linspace(0, 1.5, 5), [0, 1, 0]))
    reference = replace(sample_reference(), orientations=multiply(turning, DOWN))
    write_reference_csv(reference, tmp_path / "reference.csv", 0.08)
    again = read_reference_csv(tmp_path / "reference.csv")
    assert np.array_equal(again.orientations, reference.orientations)
    older = tmp_path / "older.csv"  # the columns before orientation was written
    older.write_text("".join(",".join(line.split(",")[:8]) + "\n" for line in (tmp_path / "reference.csv").read_text().splitlines()))
    assert read_reference_csv(older).orientations is None and np.array_equal(read_reference_csv(older).positions, reference.positions)


def test_a_bad_reference_csv_names_the_line(tmp_path):
    path = tmp_path / "reference.csv"
    path.write_text("t,x,y,z,gripper,skill,state,event\n0,0.4,0,0.3,0.08,skill,1,\n0.1,0.4,oops,0.3,0.08,skill,1,\n")
    with pytest.raises(SignalError, match=r"reference.csv:3: not a number"):
        read_reference_csv(path)


def test_the_safety_gate_names_the_time_and_the_point():
    safety = Safety((0.2, -0.5, 0.1), (0.8, 0.5, 0.8), max_speed=1.0)
    times = np.arange(4) / 10
    inside = np.array([[0.4, 0.0, 0.3], [0.41, 0.0, 0.3], [0.42, 0.0, 0.3], [0.43, 0.0, 0.3]])
    check_reference(Reference(times, inside), safety)
    low = inside.copy()
    low[2, 2] = 0.05
    with pytest.raises(UnsafeReference, match=r"t = 0.200 s it reaches \(x=0.420, y=0.000, z=0.050\), outside the workspace \(z below 0.1\)"):
        check_reference(Reference(times, low), safety)
    fast = inside.copy()
    fast[3, 0] = 0.6  # 0.18 m in 0.1 s
    with pytest.raises(UnsafeReference, match=r"t = 0.200 s it moves at 1.800 m/s .* faster than the scene's max_speed of 1 m/s"):
        check_reference(Reference(times, fast), safety)


def test_bundled_scenes_declare_safety_and_bad_limits_are_refused(tmp_path):
    for name in ("free_space", "pick_insert"):
        assert load_scene(name).safety is not None
    path = tmp_path / "scene.yaml"
    path.write_text("description: x\nsafety:\n  workspace: {lower: [0.5, 0, 0], upper: [0.4, 1, 1]}\n  max_speed: 1\n")
    with pytest.raises(ConfigError, match=r"scene.yaml:\d+:\d+: 'safety': the workspace's lower corner .* below its upper corner"):
        load_scene(path)
    path.write_text("description: x\nsafety:\n  workspace: {lower: [0, 0, 0], upper: [1, 1, 1]}\n")
    with pytest.raises(ConfigError, match="max_speed"):
        load_scene(path)


@pytest.mark.slow
def test_the_command_backend_gives_what_the_in_process_backend_gives(tmp_path, learned_model_file):
    command_task = executor_task(tmp_path, learned_model_file)
    finish_run(start_run(command_task, tmp_path / "command"))
    finish_run(start_run(command_task.with_overrides(backend="kinematic"), tmp_path / "kinematic"))
    command, kinematic = trials_of(tmp_path / "command"), trials_of(tmp_path / "kinematic")
    assert [(t["x"], t["robustness"], t["components"]) for t in command] == [(t["x"], t["robustness"], t["components"]) for t in kinematic]
    for folder in ("initial", "trial-0001", "trial-0004"):
        assert {path.name for path in (tmp_path / "command" / "executions" / folder).iterdir()} == {"reference.csv", "signals.csv", "stdout.txt", "stderr.txt"}


@pytest.mark.slow
def test_placeholders_and_environment_reach_the_command(tmp_path, learned_model_file, monkeypatch):
    monkeypatch.setenv("EXECUTOR_MODE", "env")
    finish_run(start_run(executor_task(tmp_path, learned_model_file, trials=1), tmp_path / "run"))
    folder = tmp_path / "run" / "executions" / "trial-0001"
    told = dict(line.split("=", 1) for line in (folder / "stdout.txt").read_text().splitlines())
    assert told["STLOPT_TRIAL"] == "1" and told["STLOPT_RUN_DIR"] == str((tmp_path / "run").resolve())
    assert told["STLOPT_SCENE"] == "free_space" and told["STLOPT_RATE"] == "50"
    assert told["argv"] == str([str((folder / "reference.csv").resolve()), str((folder / "signals.csv").resolve())])


@pytest.mark.parametrize(
    "mode, error, message",
    [
        ("exit1", ExecutionError, r"the command exited with status 1: motor fault on joint 4 \(see .*trial-0001/stderr.txt\)"),
        ("hang", ExecutionError, r"did not finish within its timeout of 2 s and was stopped"),
        ("garbage", SignalError, r"trial-0001/signals.csv:1: missing column 't'"),
        ("nothing", ExecutionError, r"the command exited without writing .*trial-0001/signals.csv"),
        ("delete", ExecutionError, r"trial-0001/reference.csv: the command removed or changed the reference it was given"),
    ],
)
@pytest.mark.slow
def test_a_bad_executor_is_a_clear_error(tmp_path, monkeypatch, mode, error, message):
    monkeypatch.setenv("EXECUTOR_MODE", mode)
    monkeypatch.setenv("EXECUTOR_CHILD_PID", str(tmp_path / "child.pid"))
    backend = CommandBackend(Command.parse(f"{sys.executable} {FAKE} {{reference}} {{signals}}", timeout=2), folder=tmp_path)
    backend.trial = 1
    reference = Reference(np.arange(240) / 240, np.tile([0.4, 0.0, 0.3], (240, 1)))
    with pytest.raises(error, match=message):
        execute(reference, load_scene("free_space"), backend, 50)
    if mode == "hang":  # the executor's own child was stopped with it
        from tests.processes import wait_for

        child = int((tmp_path / "child.pid").read_text())
        wait_for(lambda: not _alive(child), timeout=10.0)  # a SIGKILL is delivered asynchronously


@pytest.mark.slow
def test_a_failed_execution_fails_its_trial_and_the_run_goes_on_and_resumes(tmp_path, learned_model_file, monkeypatch):
    monkeypatch.setenv("EXECUTOR_MODE", "noforce")
    monkeypatch.setenv("EXECUTOR_BAD_TRIAL", "1")
    task = executor_task(tmp_path, learned_model_file, spec=FORCE_SPEC, trials=2)
    finish_run(start_run(task, tmp_path / "run"))
    first, second = trials_of(tmp_path / "run")
    assert first["status"] == "failed" and second["status"] == "ok"
    assert first["error"].endswith("trial-0001/signals.csv: no column force, which the spec needs")
    from stl_lfd.optim import resume_run

    finish_run(resume_run(tmp_path / "run", trials=3))
    assert [trial["status"] for trial in trials_of(tmp_path / "run")] == ["failed", "ok", "ok"]


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    status = Path(f"/proc/{pid}/stat").read_text().split()[2] if Path(f"/proc/{pid}/stat").exists() else "X"
    return status not in ("Z", "X")


@pytest.mark.slow
def test_an_unsafe_reference_never_reaches_the_command(tmp_path, learned_model_file, monkeypatch):
    scene = tmp_path / "tight.yaml"
    scene.write_text("description: tight\nsafety:\n  workspace: {lower: [0.2, -0.6, 0.1], upper: [0.8, 0.6, 0.8]}\n  max_speed: 0.6\n")
    monkeypatch.setenv("EXECUTOR_MARKER", str(tmp_path / "ran.txt"))
    task = executor_task(tmp_path, learned_model_file, trials=8, scene=str(scene))
    finish_run(start_run(task, tmp_path / "run"))
    trials = trials_of(tmp_path / "run")
    refused = [trial["trial"] for trial in trials if trial["status"] == "failed"]
    assert refused, "the tight speed limit should refuse some trials"
    for trial in trials:
        if trial["status"] == "failed":
            assert trial["error"].startswith("unsafe reference, not executed: at t = ") and "max_speed of 0.6 m/s" in trial["error"]
    ran = [int(line) for line in (tmp_path / "ran.txt").read_text().split()]
    assert ran == [0] + [trial["trial"] for trial in trials if trial["status"] == "ok"]


def test_the_command_backend_needs_a_command_and_limits(tmp_path, learned_model_file):
    task = executor_task(tmp_path, learned_model_file)
    with pytest.raises(ConfigError, match="the command backend needs the command"):
        task.with_overrides(backend="command").__class__(**{**task.__dict__, "command": None})
    with pytest.raises(ConfigError, match="empty"):
        Command.parse("   ")
    reference = Reference(np.arange(3) / 240, np.tile([0.4, 0.0, 0.3], (3, 1)))
    backend = CommandBackend(Command.parse(f"{sys.executable} {FAKE} {{reference}} {{signals}}"))
    with pytest.raises(ExecutionError, match="declares no 'safety'"):
        execute(reference, load_scene("free_space").__class__(name="bare", description="no limits"), backend)


def test_a_missing_program_is_a_clear_error():
    reference = Reference(np.arange(3) / 240, np.tile([0.4, 0.0, 0.3], (3, 1)))
    backend = CommandBackend(Command.parse("no-such-executor-xyz {reference}"))
    with pytest.raises(ExecutionError, match=r"cannot start the command 'no-such-executor-xyz' \(No such file or directory\)"):
        execute(reference, load_scene("free_space"), backend)


@pytest.mark.slow
def test_ctrl_c_stops_the_executor_with_its_children_and_keeps_the_trials(tmp_path, learned_model_file):
    import signal
    import subprocess

    from tests.processes import deliverable_sigint, interrupt, wait_for

    task = executor_task(tmp_path, learned_model_file, trials=4)
    environment = dict(os.environ, EXECUTOR_MODE="hang", EXECUTOR_BAD_TRIAL="3", EXECUTOR_CHILD_PID=str(tmp_path / "child.pid"))
    stlopt = str(Path(sys.executable).parent / "stlopt")
    process = subprocess.Popen(
        [stlopt, "optimize", str(task.source), "--out", str(tmp_path / "run")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=environment, preexec_fn=deliverable_sigint,
    )  # fmt: skip
    wait_for(lambda: (tmp_path / "child.pid").exists() and (tmp_path / "child.pid").read_text().strip() != "")  # written, not only created
    child = int((tmp_path / "child.pid").read_text())
    _, err = interrupt(process)
    assert process.returncode == -signal.SIGINT, err
    assert "the finished trials are kept" in err and "Traceback" not in err
    wait_for(lambda: not _alive(child), timeout=10.0)
    assert [trial["trial"] for trial in trials_of(tmp_path / "run")] == [1, 2]


def test_what_a_command_leaves_running_is_stopped_after_every_execution(tmp_path):
    from stl_lfd.sim.command import run_command
    from stl_lfd.sim.executor import Command
    from tests.processes import alive

    for _ in range(3):
        script = "sleep 300 & echo $! > left.pid"
        run_command(Command.parse(script, shell=True, cwd=tmp_path), {}, tmp_path)
        left = int((tmp_path / "left.pid").read_text())
        assert not alive(left) and not Path(f"/proc/{left}").exists()  # stopped and reaped: not even a zombie


def test_a_misspelt_placeholder_is_named_and_other_braces_are_the_commands():
    from stl_lfd.errors import ConfigError
    from stl_lfd.sim.executor import Command

    with pytest.raises(ConfigError, match=r"the command has \{signal\}: did you mean \{signals\}\?"):
        Command.parse("executor {reference} {signal}")
    assert Command.parse("awk '{print}' {reference}").run == ("awk", "{print}", "{reference}")


def _hanging_run(tmp_path, learned_model_file, workers=1):
    """`stlopt optimize` in a child process whose executor hangs on trial 3 (with a child of its
    own); the process, and the executor's and its child's PIDs once it hangs."""
    import subprocess

    from tests.processes import wait_for

    task = executor_task(tmp_path, learned_model_file, trials=4)
    environment = dict(os.environ, EXECUTOR_MODE="hang", EXECUTOR_BAD_TRIAL="3", EXECUTOR_CHILD_PID=str(tmp_path / "child.pid"))
    stlopt = str(Path(sys.executable).parent / "stlopt")
    process = subprocess.Popen(
        [stlopt, "optimize", str(task.source), "--out", str(tmp_path / "run"), "--workers", str(workers)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=environment,
    )  # fmt: skip
    wait_for(lambda: (tmp_path / "child.pid").exists() and (tmp_path / "child.pid").read_text().strip() != "")  # written, not only created
    recorded = json.loads((tmp_path / "run" / "executions" / "trial-0003" / "executor.json").read_text())
    return process, task, recorded["group"], int((tmp_path / "child.pid").read_text())


def test_kill_9_of_the_supervisor_stops_its_executor_and_a_resume_runs_the_trial_once(tmp_path, learned_model_file):
    from tests.processes import alive, wait_for

    process, task, executor, child = _hanging_run(tmp_path, learned_model_file)
    process.kill()  # SIGKILL: no handler runs
    process.wait()
    wait_for(lambda: not alive(executor) and not alive(child), timeout=3.0)
    import subprocess

    stlopt = str(Path(sys.executable).parent / "stlopt")
    resumed = subprocess.run(
        [stlopt, "optimize", str(task.source), "--out", str(tmp_path / "run"), "--resume", "--quiet"],
        capture_output=True, text=True, env=dict(os.environ, EXECUTOR_MARKER=str(tmp_path / "marker")),
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stderr
    assert (tmp_path / "marker").read_text().split() == ["3", "4"]  # trial 3 executed once more, then trial 4
    uninterrupted = subprocess.run([stlopt, "optimize", str(task.source), "--out", str(tmp_path / "whole"), "--quiet"], capture_output=True, text=True)
    assert uninterrupted.returncode == 0, uninterrupted.stderr
    assert [(trial["x"], trial["robustness"]) for trial in trials_of(tmp_path / "run")] == [
        (trial["x"], trial["robustness"]) for trial in trials_of(tmp_path / "whole")
    ]


def test_kill_9_of_a_worker_stops_its_executor(tmp_path, learned_model_file):
    import signal

    from tests.processes import alive, wait_for, worker_processes

    process, _, executor, child = _hanging_run(tmp_path, learned_model_file, workers=2)
    supervisor = next(pid for pid in worker_processes(process.pid) if executor in _children(pid))
    os.kill(supervisor, signal.SIGKILL)
    wait_for(lambda: not alive(executor) and not alive(child), timeout=3.0)
    process.kill()
    process.wait()


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    found.append(int(entry.name))
            except (OSError, IndexError, ValueError):
                continue
    return found


def test_a_leftover_executor_of_the_same_trial_is_stopped_before_another_starts(tmp_path):
    import subprocess

    from stl_lfd.sim.watchdog import record_group, stop_leftover
    from tests.processes import alive

    leftover = subprocess.Popen(["sleep", "300"], start_new_session=True)
    record_group(tmp_path, leftover.pid)  # as a killed supervisor left it
    assert stop_leftover(tmp_path, grace=3.0)
    leftover.wait(timeout=5)
    assert not alive(leftover.pid) and not (tmp_path / "executor.json").exists()
    assert not stop_leftover(tmp_path, grace=3.0)  # nothing left to stop
