"""Robots that do not execute the plan: kinematic executions with the ways a real arm departs
from its reference, for the suite's `PROBLEM+VARIANT` problems and the tracking benchmark.

`ImperfectRobot` reads the reference on its own clock (speed scaling: `clock` reference seconds
per second), offsets it (a calibration error), and follows it as a first-order servo of time
constant `lag` whose speed and acceleration are limited; the hand sits `sag` from where the
servo is, and the recording has Gaussian `noise`. `VARIANTS` names the settings the suite uses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd import SignalTable
from stl_lfd.sim import Capabilities, KinematicBackend, Rollout

SUBSTEPS = 10  # servo steps per recorded sample


@dataclass(frozen=True)
class ImperfectRobot(KinematicBackend):
    """A kinematic execution of the reference as a compliant, speed-scaled arm does it."""

    lag: float = 0.0  # s: time constant of the servo (0: it reaches the target at once)
    sag: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m: where the hand sits from the servo
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m: a calibration error of the target
    speed_limit: float = np.inf  # m/s
    acceleration_limit: float = np.inf  # m/s^2
    clock: float = 1.0  # reference seconds per second (0.8: the robot runs 20 % slow)
    noise: float = 0.0  # m: standard deviation of the recorded positions' noise
    seed: int = 0

    name = "kinematic"
    capabilities = Capabilities()

    def run(self, reference, scene, rate, observer=None) -> Rollout:
        rollout = super().run(reference, scene, rate, observer)
        times, columns = rollout.signals.times, dict(rollout.signals.columns)
        targets = reference.positions_at(self.clock * times) + np.asarray(self.offset)
        reached = self._servo(targets, times) + np.asarray(self.sag)
        if self.noise > 0:
            reached = reached + np.random.default_rng(self.seed).normal(0.0, self.noise, reached.shape)
        sent = reference.positions_at(times)
        for axis, name in enumerate("xyz"):
            columns[name] = reached[:, axis]
        return Rollout(SignalTable(times, columns, source="imperfect robot"), np.linalg.norm(reached - sent, axis=1))

    def _servo(self, targets: np.ndarray, times: np.ndarray) -> np.ndarray:
        """`T x 3` positions of a servo that starts at rest on the first target."""
        step = float(times[1] - times[0]) / SUBSTEPS
        position, velocity = targets[0].copy(), np.zeros(3)
        reached = np.empty_like(targets)
        reached[0] = position
        for sample in range(1, len(times)):
            for _ in range(SUBSTEPS):
                wanted = (targets[sample] - position) / max(self.lag, step)
                wanted *= min(1.0, self.speed_limit / max(np.linalg.norm(wanted), 1e-12))
                change = wanted - velocity
                velocity = velocity + change * min(1.0, self.acceleration_limit * step / max(np.linalg.norm(change), 1e-12))
                position = position + velocity * step
            reached[sample] = position
        return reached


VARIANTS = {
    "slowlag": ImperfectRobot(lag=0.2),
    "sag": ImperfectRobot(sag=(0.0, 0.0, -0.015)),
    "speed": ImperfectRobot(lag=0.05, speed_limit=0.2),
    "accel": ImperfectRobot(lag=0.1, acceleration_limit=1.5),
    "slow": ImperfectRobot(clock=0.8),
    "fast": ImperfectRobot(clock=1.1),
    "offset": ImperfectRobot(offset=(0.006, -0.005, 0.004)),
    "noise": ImperfectRobot(noise=0.002),
    "robot": ImperfectRobot(lag=0.15, sag=(0.0, 0.0, -0.008), speed_limit=0.2, acceleration_limit=0.5, clock=0.85, noise=0.0005),
}
