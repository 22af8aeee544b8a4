"""The safety gate: a reference must stay inside the scene's workspace box and below its maximum
Cartesian speed (and, if the scene sets one, its maximum angular speed of the hand) before it is
handed to anything outside stlopt (an external command, or a
trial asked for with `stlopt ask`).

The in-process backends are not gated: a simulated robot cannot be hurt, and the optimiser
should learn from what it would do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ExecutionError
from stl_lfd.sim.reference import Reference

AXES = ("x", "y", "z")


class UnsafeReference(ExecutionError):
    """A reference leaves the workspace or moves faster than allowed; it was not executed."""


@dataclass(frozen=True, repr=False)
class Safety:
    """Limits every reference must respect.

    Attributes:
        lower, upper: corners (m, robot base frame) of the box every reference position lies in.
        max_speed: the fastest Cartesian speed (m/s) a reference may ask for.
        max_angular_speed: the fastest turn of the hand (rad/s), or None for no limit.
        max_force: the largest contact force (N) a recording from outside may show, or None
            for `stl_lfd.sim.plausibility.DEFAULT_MAX_FORCE`.
    """

    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    max_speed: float
    max_angular_speed: float | None = None
    max_force: float | None = None

    def __post_init__(self) -> None:
        if not all(low < high for low, high in zip(self.lower, self.upper)):
            raise ValueError(f"the workspace's lower corner {list(self.lower)} must be below its upper corner {list(self.upper)} on every axis")
        if not self.max_speed > 0:
            raise ValueError(f"max_speed must be positive (got {self.max_speed})")
        if self.max_angular_speed is not None and not self.max_angular_speed > 0:
            raise ValueError(f"max_angular_speed must be positive (got {self.max_angular_speed})")
        if self.max_force is not None and not self.max_force > 0:
            raise ValueError(f"max_force must be positive (got {self.max_force})")

    def __repr__(self) -> str:
        # Without an angular limit, as before there was one: a scene's repr is the fingerprint
        # that lets runs started with it resume.
        angular = f", max_angular_speed={self.max_angular_speed!r}" if self.max_angular_speed is not None else ""
        force = f", max_force={self.max_force!r}" if self.max_force is not None else ""
        return f"Safety(lower={self.lower!r}, upper={self.upper!r}, max_speed={self.max_speed!r}{angular}{force})"


def check_reference(reference: Reference, safety: Safety) -> None:
    """Refuse a reference that leaves the workspace or is too fast.

    Raises:
        UnsafeReference: naming the first offending time and point.
    """
    positions, times = reference.positions, reference.times
    lower, upper = np.array(safety.lower), np.array(safety.upper)
    outside = np.any((positions < lower) | (positions > upper), axis=1)
    if outside.any():
        index = int(np.argmax(outside))
        point = positions[index]
        axis = int(np.argmax((point < lower) | (point > upper)))
        bound = f"below {lower[axis]:g}" if point[axis] < lower[axis] else f"above {upper[axis]:g}"
        raise UnsafeReference(
            f"unsafe reference, not executed: at t = {times[index]:.3f} s it reaches {_point(point)}, outside the workspace ({AXES[axis]} {bound})"
        )
    speeds = np.linalg.norm(np.diff(positions, axis=0), axis=1) / np.diff(times)
    _check_rate(speeds, safety.max_speed, "it moves at {rate} m/s", "max_speed of {limit:g} m/s", times, positions)
    if safety.max_angular_speed is not None and reference.orientations is not None:
        turns = reference.orientations
        angular = np.linalg.norm(rotations.log_map(turns[:-1], turns[1:]), axis=1) / np.diff(times)
        _check_rate(angular, safety.max_angular_speed, "the hand turns at {rate} rad/s", "max_angular_speed of {limit:g} rad/s", times, positions)


def _check_rate(rates: np.ndarray, limit: float, doing: str, allowed: str, times: np.ndarray, positions: np.ndarray) -> None:
    """UnsafeReference at the first of the `T - 1` `rates` between samples above `limit`."""
    too_fast = rates > limit
    if too_fast.any():
        index = int(np.argmax(too_fast))
        raise UnsafeReference(
            f"unsafe reference, not executed: at t = {times[index]:.3f} s {doing.format(rate=_rate(rates[index]))} near {_point(positions[index])}, "
            f"faster than the scene's {allowed.format(limit=limit)}"
        )


def _rate(rate: float) -> str:
    """Three decimals, or three significant digits for a rate too small to show in decimals."""
    return f"{rate:.3f}" if rate >= 0.001 else f"{rate:.3g}"


def _point(point: np.ndarray) -> str:
    return "(" + ", ".join(f"{name}={value:.3f}" for name, value in zip(AXES, point)) + ")"
