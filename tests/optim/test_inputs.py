"""A task is resolved once: from `stlopt optimize` to the recorded trials, every file the task
names is read once; on `--resume`, once for the run's own task and once more only where the task
file named again must be compared with it."""

import collections
from pathlib import Path

import pytest
from typer.testing import CliRunner

import stl_lfd.files
from stl_lfd.cli import app
from tests.conftest import ROOT


@pytest.fixture
def reads(monkeypatch):
    """Every text file read through `files.read_text` (YAML, specs, CSVs), counted by path."""
    counted = collections.Counter()
    original = stl_lfd.files.read_text

    def counting(path, what, max_bytes=stl_lfd.files.MAX_TEXT_BYTES):
        counted[Path(path).resolve()] += 1
        return original(path, what, max_bytes)

    for module in ("stl_lfd.files", "stl_lfd.yamlfile", "stl_lfd.stl.parser", "stl_lfd.signals"):
        monkeypatch.setattr(f"{module}.read_text", counting)
    return counted


def behaviour_task(folder: Path, model_file: Path) -> Path:
    """A task of two skills and a grasp (the same model twice, no learning), in the pick-insert
    scene, on the kinematic backend."""
    behaviour = folder / "behaviour.yaml"
    behaviour.write_text(
        f"scene: pick_insert\nsteps:\n  - {{skill: reach, model: {model_file}}}\n  - {{action: grasp, seconds: 0.5}}\n"
        f"  - {{skill: leave, model: {model_file}}}\n  - {{action: release, seconds: 0.5}}\n"
    )
    task = folder / "task.yaml"
    task.write_text(
        f"spec: {ROOT / 'specs' / 'phi1.stl'}\nbehaviour: {behaviour}\nbackend: kinematic\nduration: 44\nrate: 20\n"
        "parameters: {leave: {means: {components: [2]}}}\noptimizer: {method: random, initial: 2, trials: 3}\n"
    )
    return task


def test_optimize_and_resume_read_each_file_of_the_task_once(tmp_path, learned_model_file, reads):
    task = behaviour_task(tmp_path, learned_model_file)
    result = CliRunner().invoke(app, ["optimize", str(task), "--out", str(tmp_path / "run"), "--quiet"])
    assert result.exit_code == 0, result.stderr
    named = [task, tmp_path / "behaviour.yaml", ROOT / "specs" / "phi1.stl", ROOT / "stl_lfd" / "sim" / "scenes" / "pick_insert.yaml"]
    assert {path: reads[path.resolve()] for path in named} == {path: 1 for path in named}
    assert max(reads.values()) == 1, [path for path, count in reads.items() if count > 1]
    reads.clear()
    result = CliRunner().invoke(app, ["optimize", str(task), "--out", str(tmp_path / "run"), "--resume", "-N", "4", "--quiet"])
    assert result.exit_code == 0, result.stderr
    once = [task, tmp_path / "run" / "task.yaml", ROOT / "specs" / "phi1.stl", ROOT / "stl_lfd" / "sim" / "scenes" / "pick_insert.yaml"]
    assert {path: reads[path.resolve()] for path in once} == {path: 1 for path in once}
    assert reads[(tmp_path / "behaviour.yaml").resolve()] == 2  # once for each task file that names it: the one given, the run's
