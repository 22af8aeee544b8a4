"""Executing a skill with orientation: the reference carries the hand's orientation, the
kinematic backend records it, and the simulated Panda follows it (inverse kinematics with an
orientation target); every rollout records `qx, qy, qz, qw` and `tilt`."""

from __future__ import annotations

import numpy as np
import pytest

from stl_lfd import rotations
from stl_lfd.hsmm import learn
from stl_lfd.hsmm.demos import with_checked_orientation
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.sim import load_scene
from stl_lfd.skill import build_reference, rollout_model
from stl_lfd.stl import Spec
from tests.hsmm.pose_demos import pose_demos


@pytest.fixture(scope="module")
def pose_skill():
    return learn([with_checked_orientation(demo) for demo in pose_demos()], 5)[0]


def recorded_orientations(signals):
    return np.column_stack([signals.columns[name] for name in QUATERNION_COLUMNS])


def test_the_kinematic_backend_records_the_reference_orientation_and_tilt(pose_skill):
    rollout = rollout_model(pose_skill, load_scene("free_space"), "kinematic", rate=100)
    reference = build_reference({"skill": pose_skill})
    orientations = recorded_orientations(rollout.signals)
    assert np.max(np.linalg.norm(rotations.log_map(reference.orientations_at(rollout.signals.times), orientations), axis=1)) < 1e-9
    assert np.degrees(rollout.signals.columns["tilt"][0]) < 2 and abs(np.degrees(rollout.signals.columns["tilt"][-1]) - 90) < 2
    upright = Spec.parse("F[0, 3] G[0, 1] tilt < 0.05 & F G tilt > 1.5")  # down at the start, then sideways to the end
    assert upright.robustness(rollout.signals.columns, rollout.signals.times, semantics="classic") > 0


@pytest.mark.slow
def test_the_simulated_panda_follows_a_pose_skill(pose_skill):
    rollout = rollout_model(pose_skill, load_scene("free_space"), "pybullet", rate=100)
    errors = np.linalg.norm(
        rotations.log_map(build_reference({"skill": pose_skill}).orientations_at(rollout.signals.times), recorded_orientations(rollout.signals)), axis=1
    )
    assert rollout.tracking_rms < 0.002 and np.degrees(np.sqrt(np.mean(errors**2))) < 1.0
    assert abs(np.degrees(rollout.signals.columns["tilt"][-1]) - 90) < 2
