"""The compliant controller of both simulated Pandas: Cartesian impedance on the torque interface.

As franka_ros's `cartesian_impedance_example_controller` (and robosuite's OSC) do it, every
control step computes joint torques

    tau = J^T F + (I - J^T J#^T) tau_posture + b(q, dq)
    F   = -K e - D (v - v_d) + Lambda (a_d - dJ/dt dq)

where `e` is the hand's pose error (position, and rotation vector of the orientation error, in
the base frame), `v = J dq` its twist, `K` the translational and rotational stiffness, `D`
critically damped for the operational-space inertia `Lambda = (J M^-1 J^T)^-1`, `b` gravity
and Coriolis (compensated, as the robot's firmware does), and `tau_posture` a weak joint spring
towards a posture (`NullspacePosture`) in the nullspace of the task (`J#` the dynamically
consistent inverse).
The reference is tracked by moving the equilibrium pose along it, with its velocity `v_d` and
acceleration `a_d` fed forward, so that the arm follows a moving reference without lag and
yields to contact like a spring of stiffness `K`. Torques are clipped to the real arm's limits.

Engine-independent: a backend passes the Jacobian, mass matrix and bias forces it computes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

import stl_lfd.rotations as rotations

# The Franka Panda's joint torque limits (Nm), joints 1-7.
PANDA_TORQUE_LIMITS = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
# The rest posture (rad) the nullspace term pulls towards: elbow up, hand above the table.
REST_POSTURE = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
# Damping of the operational-space inertia's inverse near singular postures (m, rad scale).
SINGULAR_DAMPING = 1e-4
# Control steps (240 Hz) between refreshes of the operational-space inertia, damping and
# nullspace: every second step costs half as much, and the tracking error of phi1's skill is
# unchanged to 0.01 mm (the Jacobian itself is fresh at every step).
REFRESH_EVERY = 2
# How the nullspace posture is chosen (`NullspacePosture`), and how often (control steps at
# 240 Hz) the `current` posture is taken again: 10 Hz.
NULLSPACE_POSTURES = ("rest", "current")
POSTURE_EVERY = 24
_EYE6, _EYE7 = np.eye(6), np.eye(7)


@dataclass(frozen=True)
class Impedance:
    """Gains of the Cartesian impedance law.

    Attributes:
        translational_stiffness: N/m on the hand's position error.
        rotational_stiffness: Nm/rad on its orientation error.
        damping_ratio: 1 for critical damping of each direction's operational-space inertia.
        nullspace_stiffness: Nm/rad of the posture spring in the task's nullspace.
        torque_limits: Nm, joints 1-7.
    """

    translational_stiffness: float
    rotational_stiffness: float
    damping_ratio: float = 1.0
    nullspace_stiffness: float = 10.0
    torque_limits: tuple[float, ...] = PANDA_TORQUE_LIMITS

    @cached_property
    def stiffness(self) -> np.ndarray:
        """`6`: translational stiffness on x, y, z, then rotational."""
        return np.array([self.translational_stiffness] * 3 + [self.rotational_stiffness] * 3)

    @cached_property
    def upper_limits(self) -> np.ndarray:
        return np.asarray(self.torque_limits, dtype=float)

    @cached_property
    def lower_limits(self) -> np.ndarray:
        return -np.asarray(self.torque_limits, dtype=float)


def pose_error(position: np.ndarray, orientation: np.ndarray, target: np.ndarray, target_orientation: np.ndarray) -> np.ndarray:
    """`6`: position error (m) and rotation vector (rad) from the target to the hand, base frame.

    Written out for one pose: called at every control step, where numpy's general quaternion
    functions cost more than the whole control law."""
    x, y, z, w = orientation
    tx, ty, tz, tw = -target_orientation[0], -target_orientation[1], -target_orientation[2], target_orientation[3]  # the target's inverse
    turn = (
        w * tx + x * tw + y * tz - z * ty,
        w * ty - x * tz + y * tw + z * tx,
        w * tz + x * ty - y * tx + z * tw,
        w * tw - x * tx - y * ty - z * tz,
    )
    sign = -1.0 if turn[3] < 0 else 1.0  # the shorter way round
    sine = math.sqrt(turn[0] ** 2 + turn[1] ** 2 + turn[2] ** 2)
    scale = 2.0 * math.atan2(sine, sign * turn[3]) / sine if sine > 1e-12 else 2.0
    error = np.empty(6)
    error[:3] = position - target
    error[3:] = [sign * scale * turn[0], sign * scale * turn[1], sign * scale * turn[2]]
    return error


@dataclass(frozen=True)
class TaskDynamics:
    """The configuration-dependent terms of the law, refreshed once per 240 Hz step (they change
    little within it): `jacobian` (`6 x 7`), `inertia` Lambda (`6 x 6`), `damping` D (`6 x 6`,
    critically damped per direction for ratio 1: `zeta (Lambda^1/2 K^1/2 + K^1/2 Lambda^1/2)`)
    and `nullspace` (`7 x 7`, `I - J^T J#^T`)."""

    jacobian: np.ndarray
    inertia: np.ndarray
    damping: np.ndarray
    nullspace: np.ndarray


def task_dynamics(gains: Impedance, jacobian: np.ndarray, mass: np.ndarray) -> TaskDynamics:
    """`TaskDynamics` of the hand Jacobian (`6 x 7`, linear rows first) and the joint-space
    inertia (`7 x 7`)."""
    mass_inverse_jacobian = np.linalg.solve(mass, jacobian.T)  # M^-1 J^T, 7 x 6
    inertia = np.linalg.inv(jacobian @ mass_inverse_jacobian + SINGULAR_DAMPING * _EYE6)
    inertia = 0.5 * (inertia + inertia.T)
    values, vectors = np.linalg.eigh(inertia)
    inertia_root = (vectors * np.sqrt(np.maximum(values, 0.0))) @ vectors.T
    stiffness_root = np.diag(np.sqrt(gains.stiffness))
    damping = gains.damping_ratio * (inertia_root @ stiffness_root + stiffness_root @ inertia_root)
    nullspace = _EYE7 - jacobian.T @ (mass_inverse_jacobian @ inertia).T
    return TaskDynamics(jacobian, inertia, damping, nullspace)


class RefreshedDynamics:
    """`TaskDynamics` with a fresh Jacobian at every control step and the rest refreshed every
    `REFRESH_EVERY` steps (`restart` at the start of a rollout)."""

    def __init__(self, gains: Impedance) -> None:
        self.gains = gains
        self.steps = 0
        self.current: TaskDynamics | None = None

    def restart(self) -> None:
        self.steps, self.current = 0, None

    def at(self, jacobian: np.ndarray, mass: Callable[[], np.ndarray]) -> TaskDynamics:
        """The dynamics for `jacobian` (`6 x 7`); `mass()` gives the `7 x 7` joint-space inertia
        when a refresh needs it."""
        if self.current is None or self.steps % REFRESH_EVERY == 0:
            self.current = task_dynamics(self.gains, jacobian, mass())
        else:
            self.current = TaskDynamics(jacobian, self.current.inertia, self.current.damping, self.current.nullspace)
        self.steps += 1
        return self.current


def impedance_torques(
    gains: Impedance,
    dynamics: TaskDynamics,
    bias: np.ndarray,
    joints: np.ndarray,
    joint_velocities: np.ndarray,
    error: np.ndarray,
    target_twist: np.ndarray,
    target_acceleration: np.ndarray,
    jacobian_rate_term: np.ndarray,
    posture: np.ndarray = REST_POSTURE,
) -> np.ndarray:
    """`7` joint torques (Nm) of the law above, clipped to the limits.

    Args:
        gains: stiffness, damping and limits.
        dynamics: `task_dynamics` at (about) this configuration.
        bias: `7` gravity and Coriolis torques (and a declared load's weight).
        joints, joint_velocities: `7` each.
        error: `6` pose error (`pose_error`).
        target_twist, target_acceleration: `6` each, the reference's twist and its rate.
        jacobian_rate_term: `6`, dJ/dt dq: the part of the hand's acceleration that joint
            accelerations do not cause (without it the hand lags on curved paths).
        posture: `7` joints the nullspace spring pulls towards (`NullspacePosture`).
    """
    jacobian = dynamics.jacobian
    wrench = (
        -gains.stiffness * error
        - dynamics.damping @ (jacobian @ joint_velocities - target_twist)
        + dynamics.inertia @ (target_acceleration - jacobian_rate_term)
    )
    spring = gains.nullspace_stiffness * (posture - joints) - 2.0 * math.sqrt(gains.nullspace_stiffness) * joint_velocities
    torques = jacobian.T @ wrench + dynamics.nullspace @ spring + bias
    return np.minimum(np.maximum(torques, gains.lower_limits), gains.upper_limits)  # np.clip costs more on 7 values


class NullspacePosture:
    """The joints the nullspace spring pulls towards: the fixed `rest` posture (franka's example
    controller holds its initial one), or the arm's `current` posture, taken again every
    `POSTURE_EVERY` control steps, so that the spring only holds the arm near where it was a
    moment ago. With the rest posture, a hand turned far from it (the re-orient-and-insert task
    with the holder turned by 120 degrees) can drag the arm into a joint limit, where it no longer
    follows the reference. An inverse kinematics of the reference solved anew as the posture did
    no better: PyBullet's may jump to another branch of the arm's redundancy, and the spring then
    swings the wrist through it while the hand carries an object."""

    def __init__(self, mode: str = "rest") -> None:
        self.mode = mode
        self.restart()

    def restart(self) -> None:
        self.posture, self.steps = REST_POSTURE, 0

    def at(self, joints: np.ndarray) -> np.ndarray:
        """`7`: the posture for this control step, given the arm's `7` joints now."""
        if self.mode == "current" and self.steps % POSTURE_EVERY == 0:
            self.posture = np.array(joints, dtype=float)
        self.steps += 1
        return self.posture


def reference_twists(times: np.ndarray, positions: np.ndarray, orientations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`T x 6` twists (m/s, rad/s) of a reference sampled at `times` and their `T x 6` rates, by
    central differences (zero at the ends, where the reference starts and stops at rest)."""
    step = np.diff(times)
    linear = np.diff(positions, axis=0) / step[:, None]
    turns = rotations.multiply(orientations[1:], rotations.conjugate(orientations[:-1]))
    angular = rotations.to_rotvec(turns) / step[:, None]
    between = np.hstack([linear, angular])  # at the midpoints
    twists = np.zeros((len(times), 6))
    twists[1:-1] = (between[1:] + between[:-1]) / 2.0
    rates = np.zeros((len(times), 6))
    rates[1:-1] = (between[1:] - between[:-1]) / ((step[1:] + step[:-1]) / 2.0)[:, None]
    return twists, rates
