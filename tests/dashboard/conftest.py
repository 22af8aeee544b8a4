"""A folder of runs for the dashboard: a finished run, a damaged copy of it, and a sweep."""

import shutil

import pytest

from stl_lfd.optim import finish_run, load_task, start_run
from stl_lfd.optim.runs.sweep import local_results, run_sweep
from stl_lfd.optim.runs.sweep_file import load_sweep
from tests.optim.test_run import small_task
from tests.optim.test_sweep import sweep_file


@pytest.fixture(scope="module")
def runs_folder(tmp_path_factory, learned_model_file):
    folder = tmp_path_factory.mktemp("dashboard") / "runs"
    tasks = folder.parent / "tasks"
    tasks.mkdir()
    task = small_task(tasks, learned_model_file)
    finish_run(start_run(load_task(task), folder / "finished"))
    shutil.copytree(folder / "finished", folder / "damaged")
    with open(folder / "damaged" / "trials.jsonl", "a") as stream:
        stream.write("{not json\n")
    sweep = sweep_file(tasks, learned_model_file, seeds=1)
    run_sweep(load_sweep(sweep), folder / "grid", lambda cells: local_results(cells, 1))
    return folder
