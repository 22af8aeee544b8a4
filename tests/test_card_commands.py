"""The project card's commands, typed exactly as the card writes them, in a folder laid out as
the repository is (demos/, specs/, configs/)."""

import json
import shutil

import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.hsmm import load_model
from tests.conftest import ROOT

runner = CliRunner()


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    for folder in ("demos", "specs", "configs"):
        shutil.copytree(ROOT / folder, tmp_path / folder)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.slow
def test_learn_demos_learns_every_skill_into_models(checkout):
    result = runner.invoke(app, ["learn", "demos/"])
    assert result.exit_code == 0, result.stderr
    skills = sorted(path.name for path in (checkout / "demos").iterdir() if path.is_dir())
    assert sorted(path.stem for path in (checkout / "models").glob("*.npz")) == skills
    assert [line[2:] for line in result.stdout.splitlines() if line.startswith("# ")] == skills  # one table per skill
    assert "wrote models/insert.npz (6 demonstrations, K = 6, frames base, shaft, holder" in result.stderr
    assert load_model(checkout / "models" / "three_regions.npz").n_states == 6


def test_learning_several_skills_writes_nothing_when_one_fails(checkout):
    (checkout / "demos" / "insert" / "demo_02.csv").write_text("t,x,y,z\n0,0.4,0,0.3\n0.02,nan,0,0.3\n")  # the first skill
    result = runner.invoke(app, ["learn", "demos/"])
    assert result.exit_code != 0 and "demo_02.csv" in result.stderr and "Traceback" not in result.stderr
    assert not (checkout / "models").exists() or not list((checkout / "models").iterdir())


@pytest.mark.slow
def test_optimize_a_spec_runs_the_task_file_that_names_it(checkout):
    result = runner.invoke(app, ["optimize", "--spec", "specs/phi2.stl"])
    assert result.exit_code == 0, result.stderr
    assert "using the task file configs/phi2.yaml, which names specs/phi2.stl" in result.stderr
    summary = json.loads(result.stdout)
    assert summary["name"] == "phi2" and summary["trials"] == 32 and (checkout / "runs" / "phi2" / "summary.json").is_file()


def test_a_spec_without_a_task_file_gets_a_default_task_or_says_what_to_add(checkout):
    (checkout / "mine.stl").write_text('include "specs/regions.stl"\nmine := F[0, 16] L3 & G z > 0.36\n')
    missing = runner.invoke(app, ["optimize", "--spec", "mine.stl"])
    assert missing.exit_code == 5 and "no task file in configs/ names this spec; give a task file, or --demos DIR or --model FILE" in missing.stderr
    result = runner.invoke(app, ["optimize", "--spec", "mine.stl", "--demos", "demos/three_regions", "-N", "3", "-M", "2", "--quiet"])
    assert result.exit_code == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["name"] == "mine" and summary["method"] == "plan" and summary["backend"] == "pybullet" and summary["trials"] == 3
    assert summary["parameters"][:3] == ["mean[2].x", "mean[2].y", "mean[2].z"]
