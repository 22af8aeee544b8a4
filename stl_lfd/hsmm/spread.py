"""A floor under what a skill model learns of the demonstrations' spread.

Several demonstrations vary, and their variation gives each state its covariance and each
duration its standard deviation: how tightly retrieval tracks a state, and how far the
optimiser may move it (bounds of `beta` standard deviations). One demonstration does not vary:
a state where the hand rests gets a covariance of a fraction of a millimetre and a duration
of one sample's spread, so the optimiser could move nothing. `MinimumSpread` widens every
state to at least a given standard deviation in every direction, the prior a user would give
("this could be 5 mm, 5 degrees or 10 % longer elsewhere").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm.orientation import Coordinates
from stl_lfd.limits import MAX_SPREAD_ANGLE, MAX_SPREAD_DURATION, MAX_SPREAD_POSITION
from stl_lfd.spelling import spelled


@dataclass(frozen=True)
class MinimumSpread:
    """The least standard deviation of a learned state.

    Attributes:
        position: metres, for every column that is not a rotation (positions, and any other
            signal in its own unit).
        angle: radians, for the rotation vector's columns.
        duration: a fraction of each state's duration mean.
    """

    position: float
    angle: float
    duration: float

    def column_stds(self, coordinates: Coordinates, dimensions: int) -> np.ndarray:
        """`D` least standard deviations, column by column."""
        stds = np.full(dimensions, self.position)
        for block in coordinates.rotations:
            stds[block] = self.angle
        return stds


# What `stlopt learn` uses when it is given a single demonstration.
ONE_DEMONSTRATION = MinimumSpread(position=0.005, angle=math.radians(5.0), duration=0.1)


def widened(covariances: np.ndarray, stds: np.ndarray) -> np.ndarray:
    """`... x D x D` covariances with at least `stds` (`D`) of spread in every direction.

    In coordinates scaled by `stds`, eigenvalues below 1 are raised to 1: a covariance
    already wider than the floor in some direction keeps it there, and a block-diagonal
    covariance stays block-diagonal.
    """
    scaled = covariances / np.multiply.outer(stds, stds)
    values, vectors = np.linalg.eigh(scaled)
    floored = (vectors * np.maximum(values, 1.0)[..., None, :]) @ np.swapaxes(vectors, -1, -2)
    return floored * np.multiply.outer(stds, stds)


_UNITS = {"position": {"mm": 0.001, "m": 1.0}, "angle": {"deg": math.pi / 180.0, "rad": 1.0}, "duration": {"%": 0.01}}


def parse_min_spread(text: str, option: str | None = None) -> MinimumSpread | None | str:
    """`auto`, `none`, or `POSITION,ANGLE,DURATION` with units (`5mm,5deg,10%`; also `m`,
    `rad`) -> what `learn` takes. ModelError naming `option` (default: the `min_spread`
    setting as the user spells it) otherwise."""
    option = option or spelled("min_spread")
    cleaned = text.strip().lower()
    if cleaned in ("auto", "none"):
        return None if cleaned == "none" else "auto"
    parts = [part.strip() for part in cleaned.split(",")]
    values = []
    if len(parts) == 3:
        for part, units in zip(parts, _UNITS.values()):
            unit = next((unit for unit in sorted(units, key=len, reverse=True) if part.endswith(unit)), None)
            number = _number(part[: -len(unit)]) if unit else None
            if number is None or not number > 0:
                break
            values.append(number * units[unit])
    if len(values) != 3:
        raise ModelError(f"{option} {text}: give auto, none, or a position, an angle and a share of the duration, with units, such as 5mm,5deg,10%")
    limits = (MAX_SPREAD_POSITION, MAX_SPREAD_ANGLE, MAX_SPREAD_DURATION)
    if any(value > limit for value, limit in zip(values, limits)):
        raise ModelError(f"{option} {text}: at most 1m, 180deg and 1000% (a wider state is no longer the demonstrated skill)")
    return MinimumSpread(*values)


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None
