"""The trials of one run on a Ray cluster (`optimize --ray`): a local cluster of two nodes, one
CPU each, so that a batch's two trials run on different nodes."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from stl_lfd.optim import finish_run, load_task, start_run
from tests.optim.test_run import small_task
from tests.processes import wait_for

pytestmark = [pytest.mark.slow, pytest.mark.heavy, pytest.mark.xdist_group("ray")]  # one Ray at a time (test_sweep.py)

TRIALS = 6


@pytest.fixture(scope="module")
def cluster():
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    cluster.add_node(num_cpus=1)
    cluster.wait_for_nodes()
    yield cluster
    cluster.shutdown()


@pytest.fixture(scope="module")
def pybullet_task(tmp_path_factory, learned_model_file):
    folder = tmp_path_factory.mktemp("ray")
    path = small_task(folder, learned_model_file)
    path.write_text(path.read_text().replace("backend: kinematic", "backend: pybullet").replace("initial: 3, trials: 5", f"initial: 2, trials: {TRIALS}"))
    return path


@pytest.fixture(scope="module")
def local_trials(tmp_path_factory, pybullet_task):
    """The same run with two local worker processes."""
    out = tmp_path_factory.mktemp("local") / "run"
    finish_run(start_run(load_task(pybullet_task).with_overrides(workers=2), out))
    return trials_of(out)


def trials_of(run: Path) -> list[dict]:
    lines = [json.loads(line) for line in (run / "trials.jsonl").read_text().splitlines()]
    return [{key: line[key] for key in ("trial", "x", "robustness", "status")} for line in lines]


def optimize_on_ray(task: Path, out: Path, address: str) -> subprocess.Popen:
    stlopt = str(Path(sys.executable).parent / "stlopt")
    command = [stlopt, "optimize", str(task), "--out", str(out), "--workers", "2", "--ray", address, "--quiet"]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def evaluating_workers() -> list[int]:
    """The Ray worker processes in the middle of a trial (Ray titles them by the task)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            command = (entry / "cmdline").read_bytes() if entry.name.isdigit() else b""
        except OSError:
            continue
        if command.startswith(b"ray::evaluate_trial"):
            found.append(int(entry.name))
    return found


def test_trials_on_a_two_node_cluster_equal_the_local_workers(tmp_path, cluster, pybullet_task, local_trials):
    process = optimize_on_ray(pybullet_task, tmp_path / "run", cluster.address)
    out, err = process.communicate(timeout=600)
    assert process.returncode == 0, err
    assert out.startswith("{"), out
    assert json.loads(out)["trials"] == TRIALS
    assert trials_of(tmp_path / "run") == local_trials


def test_a_node_that_dies_mid_trial_has_its_trial_run_again_elsewhere(tmp_path, cluster, pybullet_task, local_trials):
    process = optimize_on_ray(pybullet_task, tmp_path / "run", cluster.address)
    trials = tmp_path / "run" / "trials.jsonl"
    wait_for(lambda: trials.exists() and len(trials.read_text().splitlines()) >= 2 and len(evaluating_workers()) == 2, timeout=300)
    worker_node = next(node for node in cluster.worker_nodes)
    cluster.remove_node(worker_node)  # its trial in flight is lost there; the head node runs it again
    try:
        out, err = process.communicate(timeout=600)
    finally:
        cluster.add_node(num_cpus=1)  # the cluster as the other tests expect it
        cluster.wait_for_nodes()
    assert process.returncode == 0 and "Traceback" not in err, err
    assert json.loads(out)["trials"] == TRIALS
    assert trials_of(tmp_path / "run") == local_trials


def test_a_worker_killed_mid_trial_has_its_trial_run_again_and_recorded_once(tmp_path, cluster, pybullet_task, local_trials):
    process = optimize_on_ray(pybullet_task, tmp_path / "run", cluster.address)
    trials = tmp_path / "run" / "trials.jsonl"
    wait_for(lambda: trials.exists() and len(trials.read_text().splitlines()) >= 2 and evaluating_workers(), timeout=300)
    killed = len(trials.read_text().splitlines())
    os.kill(evaluating_workers()[0], signal.SIGKILL)
    out, err = process.communicate(timeout=600)
    assert process.returncode == 0 and "Traceback" not in err, err
    assert json.loads(out)["trials"] == TRIALS  # Ray's messages about the dead worker are on stderr, not in the JSON
    assert killed < TRIALS  # the kill came before the last trial was recorded
    assert trials_of(tmp_path / "run") == local_trials  # nothing lost, nothing twice
    assert all((tmp_path / "run" / "signals" / f"trial-{number:04d}.csv").is_file() for number in range(1, TRIALS + 1))


def test_what_ray_says_when_it_cannot_join_is_one_line_naming_the_cause():
    from stl_lfd.errors import ConfigError
    from stl_lfd.optim.runs.ray_workers import join_problem, split_address

    assert split_address("10.0.0.5:6379") == ("10.0.0.5", 6379) and split_address("ray://head:10001") == ("head", 10001)
    assert split_address("[::1]:6379") == ("::1", 6379)
    for bad in ("head", "head:port", ":6379x", "a b:6379", "head:0"):
        with pytest.raises(ConfigError, match="not a cluster address"):
            split_address(bad)
    refused = RuntimeError("Failed to connect to GCS: status Unauthenticated: invalid token.\nmore lines")
    assert "RAY_AUTH_MODE=token" in join_problem(refused) and "\n" not in join_problem(refused)
    assert join_problem(ConnectionError("Could not find any running Ray instance. Please specify ...")) == "Could not find any running Ray instance"


def test_a_head_that_stops_answering_ends_the_run_with_one_line_and_the_resume_hint():
    script = (
        "import socket, time\n"
        "from stl_lfd.optim.runs.ray_workers import watch_head\n"
        "head = socket.socket(); head.bind(('127.0.0.1', 0)); head.listen()\n"
        "watch_head('127.0.0.1:%d' % head.getsockname()[1], every=0.1, patience=0.5)\n"
        "time.sleep(1.0); head.close(); time.sleep(30)\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert result.returncode == 9
    assert result.stderr.startswith("error: ") and result.stderr.count("\n") == 1  # options are spelled 'ray' outside the command line
    assert (
        "127.0.0.1:" in result.stderr
        and "the cluster's head stopped answering; the recorded trials are kept: continue the run with the same command and" in result.stderr
    )
