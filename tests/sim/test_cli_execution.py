"""`stlopt rollout` and `stlopt replay` as a user runs them."""

import imageio.v2 as imageio
import numpy as np
import pytest
from typer.testing import CliRunner

from stl_lfd.choices import RECORDED_SIGNALS
from stl_lfd.cli import app
from stl_lfd.hsmm import save_model
from stl_lfd.signals import read_signal_csv
from tests.conftest import ROOT

runner = CliRunner()
PHI1 = str(ROOT / "specs" / "phi1.stl")


@pytest.mark.slow
def test_rollout_writes_csv_to_stdout_for_a_pipeline(learned_model_file):
    result = runner.invoke(app, ["rollout", str(learned_model_file), "--duration", "20", "--rate", "50"])
    assert result.exit_code == 0, result.stderr
    assert result.stdout.startswith("t,x,y,z,gripper,force,qx,qy,qz,qw,tilt,fx,fy,fz,tx,ty,tz\n")
    assert "x real time" in result.stderr and "tracking error RMS" in result.stderr
    piped = runner.invoke(app, ["robustness", PHI1, "-", "--semantics", "new"], input=result.stdout)
    assert piped.exit_code == 0, piped.stderr
    assert float(piped.stdout) < 0  # the learned skill violates phi1 (the optimiser fixes it)
    assert "violated" in piped.stderr


def test_rollout_to_a_file(learned_model_file, tmp_path):
    output = tmp_path / "signals.csv"
    result = runner.invoke(app, ["rollout", str(learned_model_file), "--backend", "kinematic", "-o", str(output), "--duration", "5"])
    assert result.exit_code == 0, result.stderr
    assert result.stdout == ""
    assert "5.00 s of the reference played back (no dynamics)" in result.stderr and "real time" not in result.stderr
    table = read_signal_csv(output)
    assert table.samples == 501 and set(table.columns) == set(RECORDED_SIGNALS)
    assert np.allclose(table.columns["qx"], 1.0) and np.allclose(table.columns["tilt"], 0.0)  # the hand points straight down


@pytest.mark.parametrize(
    "arguments, code, message",
    [
        (["rollout", "missing.npz"], 6, "missing.npz"),
        (["rollout", "{model}", "--scene", "kitchen"], 5, "unknown scene 'kitchen'"),
        (["rollout", "{model}", "--rate", "0"], 6, "the rate must be a positive number"),
        (["rollout", "{model}", "--backend", "gazebo"], 2, "gazebo"),
        (["replay", "missing.npz", "--video", "x.gif"], 5, "no such model file, behaviour file or run directory"),
        (["replay", "{model}", "--video", "x.avi"], 8, "must end in .mp4 or .gif"),
    ],
)
def test_bad_input_gives_one_error_line(learned_model_file, arguments, code, message):
    arguments = [argument.replace("{model}", str(learned_model_file)) for argument in arguments]
    result = runner.invoke(app, arguments)
    assert result.exit_code == code, result.stderr
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_a_model_with_nan_is_refused(learned_model, tmp_path):
    broken = tmp_path / "broken.npz"
    save_model(learned_model, broken)
    with np.load(broken, allow_pickle=False) as data:
        fields = {name: data[name] for name in data.files}
    fields["means"][2, 0] = np.nan
    np.savez(broken, **fields)
    result = runner.invoke(app, ["rollout", str(broken)])
    assert result.exit_code == 6
    assert "NaN" in result.stderr


def test_gui_without_a_display_is_a_clear_error(learned_model_file, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    result = runner.invoke(app, ["replay", str(learned_model_file), "--gui"])
    assert result.exit_code == 7
    assert result.stderr.strip() == "error: --gui needs a display and DISPLAY is not set; record a video with --video FILE.mp4 instead"


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_headless_replay_writes_a_video_with_one_frame_per_tick(learned_model_file, tmp_path, suffix):
    video = tmp_path / f"replay{suffix}"
    result = runner.invoke(app, ["replay", str(learned_model_file), "--spec", PHI1, "--duration", "1", "--video", str(video)])
    assert result.exit_code == 0, result.stderr
    fps = 24
    expected = 1 * fps + 1
    assert f"({expected} frames)" in result.stderr
    frames = [frame for frame in imageio.get_reader(video)]
    assert len(frames) == expected
    assert frames[0].shape[:2] == (360, 480)
    assert frames[0].std() > 10  # a picture, not a blank frame
    float(result.stdout)  # the robustness of the replayed execution
    assert not list(tmp_path.glob(".*partial*"))
