"""Backends are found by name in one registry and say what they can do in their capabilities."""

from __future__ import annotations

import ast

import numpy as np
import pytest

from stl_lfd.errors import ConfigError, ExecutionError
from stl_lfd.sim import Reference, execute, load_scene
from stl_lfd.sim import registry as registry_module
from stl_lfd.sim.backend import BackendBase, BackendOptions, Capabilities
from stl_lfd.sim.recorder import Recorder
from stl_lfd.sim.reference import TIME_STEP


class ToyBackend(BackendBase):
    """A robot whose hand sits 1 cm above where it is sent and feels a constant 2 N downwards."""

    name = "toy"
    capabilities = Capabilities(simulates=True, measures_force=True)

    def run(self, reference, scene, rate, observer=None):
        step_times = np.arange(int(round(reference.duration / TIME_STEP)) + 1) * TIME_STEP
        recorder = Recorder(step_times, len(scene.frames))
        frames = (np.array([frame.pose.position for frame in scene.frames]).reshape(-1, 3), np.tile([0.0, 0.0, 0.0, 1.0], (len(scene.frames), 1)))
        for step, (position, orientation) in enumerate(zip(reference.positions_at(step_times), reference.orientations_at(step_times))):
            recorder.record(
                step, (position + [0.0, 0.0, 0.01], orientation), 0.08, np.array([0.0, 0.0, -2.0, 0.0, 0.0, 0.0]), frames, np.zeros(len(scene.frames))
            )
            if observer is not None:
                observer(step_times[step], self)
        return recorder.rollout(reference, scene, rate, "toy rollout")


@pytest.fixture
def toy_registered(monkeypatch):
    monkeypatch.setitem(registry_module.REGISTRY, "toy", registry_module.Entry(ToyBackend, "a toy robot"))


def test_a_new_backend_is_one_class_and_one_registry_line(toy_registered):
    times = np.linspace(0.0, 2.0, 21)
    reference = Reference(times, np.column_stack([0.4 + 0.05 * times, np.zeros_like(times), np.full_like(times, 0.3)]))
    scene = load_scene("pick_insert")
    rollout = execute(reference, scene, "toy", rate=50.0)
    signals = rollout.signals
    assert list(signals.columns) == list(scene.recorded_signals)
    assert np.allclose(signals.columns["z"], 0.31) and np.allclose(signals.columns["x"], 0.4 + 0.05 * signals.times)
    assert np.allclose(signals.columns["force"], 2.0) and np.allclose(signals.columns["fz"], -2.0)
    assert np.allclose(signals.columns["shaft_x"], 0.45) and np.allclose(rollout.tracking_error, 0.01)
    assert "toy" in registry_module.backend_names()


def test_capabilities_are_declared_not_probed():
    from stl_lfd.sim import backend_class

    assert backend_class("kinematic").capabilities.plays_the_plan
    assert not backend_class("pybullet").capabilities.plays_the_plan and backend_class("pybullet").capabilities.films
    assert backend_class("command").capabilities.needs_command and not backend_class("command").capabilities.films


def test_unknown_backends_commands_and_windows_are_refused():
    with pytest.raises(ExecutionError, match="unknown backend 'gazebo' \\(choose from pybullet"):
        registry_module.new_backend("gazebo")
    with pytest.raises(ConfigError, match="needs a command"):
        registry_module.new_backend("command")
    with pytest.raises(ExecutionError, match="the kinematic backend has no GUI"):
        registry_module.new_backend("kinematic", BackendOptions(gui=True))


def test_no_backend_name_is_spelled_outside_the_registry_and_the_backends():
    """Code chooses by capability, not by comparing names (docstrings may show examples)."""
    from tests.conftest import ROOT

    names = set(registry_module.backend_names()) - {"command"}  # 'command' is also a task key
    homes = {"registry.py", "pybullet_panda.py", "mujoco_panda.py", "kinematic.py", "command.py"}
    spelled = []
    for path in sorted((ROOT / "stl_lfd").rglob("*.py")):
        if path.name in homes:
            continue
        tree = ast.parse(path.read_text())
        docstrings = {id(node.value) for node in ast.walk(tree) if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)}
        spelled += [
            f"{path.name}:{node.lineno}: {node.value}"
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and node.value in names and id(node) not in docstrings
        ]
    assert spelled == []
