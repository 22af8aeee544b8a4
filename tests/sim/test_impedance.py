"""The compliant controller's law and the wrist sensor's compensation, on their own."""

from __future__ import annotations

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.sim.impedance import REST_POSTURE, Impedance, impedance_torques, pose_error, reference_twists, task_dynamics
from stl_lfd.sim.world import GRAVITY, cross, external_wrench

GAINS = Impedance(400.0, 20.0)


def random_quaternions(rng, count):
    quaternions = rng.normal(size=(count, 4))
    return quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)


def test_the_pose_error_is_the_position_difference_and_the_shorter_rotation_vector():
    rng = np.random.default_rng(0)
    for hand, target in zip(random_quaternions(rng, 500), random_quaternions(rng, 500)):
        error = pose_error(np.array([0.1, 0.2, 0.3]), hand, np.array([0.1, 0.25, 0.2]), target)
        assert np.allclose(error[:3], [0.0, -0.05, 0.1])
        assert np.allclose(error[3:], rotations.to_rotvec(rotations.multiply(hand, rotations.conjugate(target))), atol=1e-9)
        assert np.linalg.norm(error[3:]) <= np.pi + 1e-9


def test_nullspace_torques_do_not_move_the_hand_and_the_spring_pulls_back():
    rng = np.random.default_rng(1)
    rows, _ = np.linalg.qr(rng.normal(size=(7, 6)))
    jacobian = rows.T  # an arm away from singular postures: singular values 1
    root = rng.normal(size=(7, 7))
    mass = root @ root.T / 7 + np.eye(7)
    dynamics = task_dynamics(GAINS, jacobian, mass)
    posture = rng.normal(size=7)
    moved = jacobian @ np.linalg.solve(mass, posture)
    # up to the small damping of the operational-space inertia's inverse
    assert np.linalg.norm(jacobian @ np.linalg.solve(mass, dynamics.nullspace @ posture)) < 1e-3 * np.linalg.norm(moved)
    # at rest with the hand 1 cm beyond the target in x, the wrench is -K e: 4 N back
    wide = Impedance(400.0, 20.0, torque_limits=(1e6,) * 7)
    torques = impedance_torques(wide, dynamics, np.zeros(7), np.zeros(7), np.zeros(7), np.array([0.01, 0, 0, 0, 0, 0]), np.zeros(6), np.zeros(6), np.zeros(6))
    wrench = np.linalg.lstsq(jacobian.T, torques - dynamics.nullspace @ (wide.nullspace_stiffness * REST_POSTURE), rcond=None)[0]
    assert np.allclose(wrench, [-4.0, 0, 0, 0, 0, 0], atol=1e-9)


def test_torques_stay_within_the_arms_limits():
    rng = np.random.default_rng(2)
    jacobian = rng.normal(size=(6, 7))
    dynamics = task_dynamics(GAINS, jacobian, np.eye(7))
    torques = impedance_torques(GAINS, dynamics, np.zeros(7), np.zeros(7), np.zeros(7), np.full(6, 10.0), np.zeros(6), np.zeros(6), np.zeros(6))
    assert np.all(np.abs(torques) <= np.asarray(GAINS.torque_limits)) and np.abs(torques).max() == pytest.approx(87.0)


def test_reference_twists_of_a_steady_screw_motion():
    times = np.arange(0.0, 2.0, 1 / 240)
    positions = np.column_stack([0.1 * times, np.zeros_like(times), 0.3 + 0.05 * times])
    orientations = rotations.multiply(rotations.from_rotvec(np.outer(0.5 * times, [0.0, 0.0, 1.0])), rotations.DOWN)
    twists, accelerations = reference_twists(times, positions, orientations)
    assert np.allclose(twists[1:-1], [0.1, 0.0, 0.05, 0.0, 0.0, 0.5], atol=1e-9)
    assert np.allclose(accelerations[1:-1], 0.0, atol=1e-6) and np.all(twists[[0, -1]] == 0.0)


def test_a_held_load_at_rest_or_swung_reads_no_external_wrench():
    rng = np.random.default_rng(3)
    masses = np.array([0.81, 0.1, 0.1, 0.05])
    centres = rng.normal(scale=0.05, size=(4, 3)) + [0.5, 0.0, 0.3]
    accelerations = rng.normal(size=(4, 3))
    flange, tool = np.array([0.5, 0.0, 0.4]), np.array([0.5, 0.0, 0.3])
    inertial = masses[:, None] * (accelerations - GRAVITY)
    # what the flange must exert to move those bodies so, and no more: the environment exerts nothing
    flange_force = inertial.sum(axis=0)
    flange_torque = cross(centres - flange, inertial).sum(axis=0)
    assert np.allclose(external_wrench(flange_force, flange_torque, flange, tool, masses, centres, accelerations), 0.0, atol=1e-12)
    # pressing on a table with 5 N at the tool point: the flange pushes 5 N more, the wrist reads +5 N up
    pressed = external_wrench(
        flange_force - [0, 0, 5.0], flange_torque - cross(tool - flange, np.array([0, 0, 5.0])), flange, tool, masses, centres, accelerations
    )
    assert np.allclose(pressed, [0, 0, 5.0, 0, 0, 0], atol=1e-12)
