"""Choosing K by held-out likelihood (`stlopt learn -K auto`)."""

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.errors import ModelError
from stl_lfd.hsmm import load_model
from stl_lfd.hsmm.states_choice import AUTO_STATES, choose_states, parse_states

runner = CliRunner()
PLATEAUS = np.array([[0.4, -0.2, 0.3], [0.5, 0.1, 0.3], [0.4, 0.3, 0.2]])  # m: where the demonstrations rest


def write_demos(folder: Path, count: int = 4) -> Path:
    """`count` demonstrations that rest at three places in turn for 2-3 s each, with a
    millimetre of noise: three states explain them."""
    folder.mkdir()
    rng = np.random.default_rng(0)
    for index in range(count):
        stays = rng.uniform(2.0, 3.0, size=len(PLATEAUS))
        positions = np.concatenate([np.tile(place, (int(stay * 20), 1)) for place, stay in zip(PLATEAUS, stays)])
        positions += rng.normal(scale=0.001, size=positions.shape)
        times = np.arange(len(positions)) * 0.05
        rows = "\n".join(f"{t:.2f},{x:.5f},{y:.5f},{z:.5f}" for t, (x, y, z) in zip(times, positions))
        (folder / f"demo_{index + 1:02d}.csv").write_text("t,x,y,z\n" + rows + "\n")
    return folder


def test_parse_states_reads_a_number_auto_or_a_range():
    assert parse_states("6") == 6
    assert parse_states("auto") == AUTO_STATES
    assert parse_states("3-8") == range(3, 9)
    for text in ("3-x", "0", "8-3", "six"):
        with pytest.raises(ModelError, match="K must be"):
            parse_states(text)


def test_the_held_out_score_chooses_the_states_the_demonstrations_have(tmp_path: Path):
    choice = choose_states(write_demos(tmp_path / "demos"), range(1, 6))
    assert choice.chosen == 3
    assert choice.scores[3].mean > choice.scores[2].mean + 5 * choice.scores[3].standard_error
    assert all(score is None or score.mean <= choice.scores[3].mean + choice.scores[3].standard_error for score in choice.scores.values())


def test_learn_with_k_auto_prints_the_table_and_writes_the_chosen_model(tmp_path: Path):
    demos = write_demos(tmp_path / "demos")
    result = runner.invoke(app, ["learn", str(demos), "-K", "2-4", "-o", str(tmp_path / "m.npz")])
    assert result.exit_code == 0, result.stderr
    rows = [line.split("\t")[0] for line in result.stderr.splitlines() if line[:1].isdigit()]
    assert rows == ["2", "3", "4"]
    assert "K = 3 (chosen" in result.stderr
    assert load_model(tmp_path / "m.npz").n_states == 3
    assert len(result.stdout.strip().splitlines()) == 4  # the header and the three states


def test_k_auto_needs_two_demonstrations_and_a_readable_k(tmp_path: Path):
    demos = write_demos(tmp_path / "demos", count=1)
    result = runner.invoke(app, ["learn", str(demos), "-K", "auto", "-o", str(tmp_path / "m.npz")])
    assert result.exit_code != 0 and "needs at least two" in result.stderr and "Traceback" not in result.stderr
    result = runner.invoke(app, ["learn", str(demos), "-K", "3-x", "-o", str(tmp_path / "m.npz")])
    assert result.exit_code != 0 and result.stderr.strip().count("\n") == 0 and "K must be" in result.stderr
    assert not (tmp_path / "m.npz").exists()
