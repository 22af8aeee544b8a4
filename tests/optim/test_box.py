"""`stlopt optimize --dry-run`: the search box in the user's units and what its plans say."""

import numpy as np
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.optim.box import _shown, corners
from tests.optim.test_run import small_task

runner = CliRunner()


def test_every_corner_of_a_small_box_and_a_fixed_sample_of_a_large_one():
    lower, upper = np.zeros(3), np.ones(3)
    assert sorted(map(tuple, corners(lower, upper, 64))) == sorted({(a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1)})
    large = corners(np.zeros(7), np.ones(7), 64)
    assert large.shape == (64, 7) and len(np.unique(large, axis=0)) == 64  # distinct corners, though drawn
    assert set(np.unique(large)) == {0.0, 1.0} and np.array_equal(large, corners(np.zeros(7), np.ones(7), 64))


def test_parameters_are_shown_in_millimetres_degrees_and_seconds():
    assert _shown("mean[2].x", 0.4, 0.39, 0.41) == ("mm", 400.0, 390.0, 410.0)
    assert _shown("insert.orient[5].holder.rz", np.pi, 0.0, np.pi / 2)[:2] == ("deg", 180.0)
    assert _shown("duration[3]", 2.0, 1.5, 2.5)[0] == "s" and _shown("transition[2->3]", 0.5, 0.0, 1.0)[0] == ""


def test_a_dry_run_prints_the_box_and_the_plans_and_writes_no_run(tmp_path, learned_model_file, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["optimize", str(small_task(tmp_path, learned_model_file)), "--dry-run"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].split() == ["parameter", "unit", "unoptimised", "lower", "upper"] and lines[1].split()[:2] == ["mean[2].x", "mm"]
    whole = next(line for line in lines if line.startswith("the whole spec")).split()
    assert float(whole[3]) <= float(whole[5]) and int(whole[6]) <= 2 + 64  # the unoptimised plan, then the best of them
    assert not (tmp_path / "runs").exists()
