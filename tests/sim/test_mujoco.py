"""The MuJoCo backend as a user meets it: its model, its videos, its error without OpenGL, and
rollouts that repeat exactly on both simulators whatever ran before them."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import imageio.v2 as imageio
import numpy as np
import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.sim import TrackingWarning, execute, load_scene, new_backend
from tests.sim.test_grasp import pick_and_place

runner = CliRunner()


def test_the_model_holds_the_scene_the_motors_and_the_wrist_sensor():
    from stl_lfd.sim.mujoco_model import build_model

    scene = load_scene("pick_insert")
    model = build_model(scene)
    assert model.body("shaft").mass[0] == pytest.approx(0.05) and model.body("shaft").jntnum[0] == 1  # free to move
    assert model.body("holder_left").jntnum[0] == 0  # fixed to the world
    assert [model.actuator(index).ctrlrange[1] for index in range(7)] == list(scene.control.torque_limits)
    assert model.actuator(7).forcerange[1] == scene.control.finger_force
    assert {model.sensor(index).name for index in range(model.nsensor)} == {"wrist_force", "wrist_torque"}


@pytest.mark.slow
def test_replay_films_a_skill_in_mujoco(learned_model_file, tmp_path):
    video = tmp_path / "skill.mp4"
    result = runner.invoke(app, ["replay", str(learned_model_file), "--backend", "mujoco", "--video", str(video), "--duration", "1"])
    assert result.exit_code == 0, result.stderr
    frames = imageio.mimread(video)
    assert len(frames) == 25 and frames[0].shape == (360, 480, 3)
    assert np.ptp(np.asarray(frames[0], dtype=float)) > 50  # a picture, not a blank frame


def test_without_its_opengl_library_mujoco_says_so_in_one_line(learned_model_file):
    environment = dict(os.environ, MUJOCO_GL="bogus")
    command = [sys.executable, "-m", "stl_lfd.cli", "rollout", str(learned_model_file), "--backend", "mujoco", "--duration", "1"]
    result = subprocess.run(command, capture_output=True, text=True, env=environment)
    assert result.returncode != 0 and result.stdout == ""
    assert result.stderr.count("\n") == 1 and "MuJoCo cannot start with MUJOCO_GL=bogus" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_a_grasp_rollout_repeats_exactly_in_the_same_world_and_in_a_new_one(engine):
    scene, reference = load_scene("pick_insert"), pick_and_place(offset=(0.012, 0.0))  # pushes on the holder
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        with new_backend(engine) as backend:
            first, second = execute(reference, scene, backend), execute(reference, scene, backend)
        with new_backend(engine) as backend:
            fresh = execute(reference, scene, backend)
    for name, values in first.signals.columns.items():
        assert np.array_equal(values, second.signals.columns[name]) and np.array_equal(values, fresh.signals.columns[name]), name


def test_mujoco_gl_glfw_without_a_display_is_one_error_and_empty_means_unset(monkeypatch):
    import os

    import pytest

    from stl_lfd.errors import ExecutionError
    from stl_lfd.sim.mujoco_panda import _mujoco

    monkeypatch.setenv("MUJOCO_GL", "glfw")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(ExecutionError, match="MUJOCO_GL=glfw: it needs a display, and DISPLAY is not set"):
        _mujoco()
    monkeypatch.setenv("MUJOCO_GL", "")
    _mujoco()
    assert os.environ["MUJOCO_GL"] == "egl"
