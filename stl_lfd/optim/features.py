"""What the GP of method `stl` sees of a point: the skill as it will be executed.

A skill is executed along a state path (`HSMM.nominal_path`: from the most likely first state,
the most likely successor of each), each state held for its duration mean. Its transition
entries act only through the path they select, a step function of them; the means of states
off the path do not act at all; and what a temporal spec sees of the durations is when each
state starts, a sum of the durations before it. A GP on the raw point must learn steps,
irrelevant directions and sums from a few trials. `PathFeatures` gives it instead, per skill
whose durations or transitions are optimised:

- the means of the states on the path (those of skipped states at the middle of their range);
- the second at which each state on the path starts, and at which the path ends (the next
  skill of a behaviour starts from there), scaled to the unit interval over the box (skipped
  states at the middle); a time that never varies is left out;
- with transition entries, one indicator per state (on the path or not).

Two points that execute alike are then the same input.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.space import ParameterSpace, SearchSpace

if TYPE_CHECKING:  # torch loads on first use: handing out a run's Sobol trials does not need it
    import torch

SKIPPED = 0.5  # a skipped state's features, in the unit cube
SCALE_POINTS = 1024  # Sobol points of the box whose paths give each time's range


@dataclass(frozen=True)
class SkillSlots:
    """Where one skill's parameters sit in a point, and what it starts from.

    Attributes:
        start: index of the skill's first parameter in the point.
        space: the skill's parameter space.
        transmat: `K x K` the model's transition matrix (as stored: `ParameterSpace.apply`
            writes the point's entries into it before renormalising).
        first_state: the most likely first state.
        duration_means: `K` the model's duration means, in seconds.
    """

    start: int
    space: ParameterSpace
    transmat: np.ndarray
    first_state: int
    duration_means: np.ndarray

    @property
    def states(self) -> int:
        return len(self.transmat)

    @property
    def modelled(self) -> bool:
        """Whether the skill's path or timing depends on the point."""
        return bool(self.space.duration_slots or self.space.transition_slots)

    def positions(self, points: np.ndarray) -> np.ndarray:
        """`b x K`: where each state comes on each of `b x d` points' path (0 first; -1 off
        the path); points in the task's units. The path is `space.apply(model,
        point).nominal_path()`."""
        space, count, K = self.space, len(points), self.states
        transmat = np.clip(np.broadcast_to(self.transmat, (count, K, K)).copy(), 0.0, None)
        if space.transition_slots:
            columns = space.transition_columns
            entries = np.clip(points[:, self.start + columns], space.lower[columns], space.upper[columns])
            sources, targets = zip(*space.transition_slots)
            transmat[:, sources, targets] = np.clip(entries, 0.0, None)
        positions = np.full((count, K), -1)
        rows = np.arange(count)
        state = np.full(count, self.first_state)
        positions[rows, state] = 0
        walking = np.ones(count, dtype=bool)
        for step in range(1, K):
            outgoing = transmat[rows, state]  # b x K
            successor = np.argmax(outgoing, axis=1)  # ties to the lower state, as nominal_path
            walking &= (outgoing.sum(axis=1) > 0) & (positions[rows, successor] < 0)
            positions[rows[walking], successor[walking]] = step
            state = np.where(walking, successor, state)
        return positions

    def visited(self, points: np.ndarray) -> np.ndarray:
        """`b x K` booleans: the states on each of `b x d` points' path."""
        return self.positions(points) >= 0

    def times(self, points: torch.Tensor, positions: np.ndarray) -> torch.Tensor:
        """`b x (K + 1)` seconds: when each state starts on each point's path (0 for the first,
        meaningless off the path), then when the path ends; differentiable in the durations.

        Args:
            points: `b x d` points in the task's units.
            positions: `b x K` the points' `positions`.
        """
        import torch

        durations = torch.as_tensor(self.duration_means, dtype=points.dtype).expand(len(points), -1).clone()
        durations[:, list(self.space.duration_slots)] = points[:, self.start + self.space.duration_columns]
        on_path = positions >= 0
        before = on_path[:, :, None] & (positions[:, :, None] < positions[:, None, :])  # b x j x k: j before k
        counted = np.concatenate([before, on_path[:, :, None]], axis=2)  # the end: after every state
        return torch.einsum("bjk,bj->bk", torch.as_tensor(counted, dtype=points.dtype), durations)


@dataclass(frozen=True)
class TimeScale:
    """The times of a skill that vary over the box (`columns` of `SkillSlots.times`), and
    their least and largest values on the paths of `SCALE_POINTS` Sobol points of it."""

    columns: np.ndarray
    low: np.ndarray
    high: np.ndarray


class PathFeatures:
    """The GP inputs of points of a `SearchSpace` whose skills have durations or transition
    entries optimised.

    Call with `b x d` points in the unit cube of the space's bounds (a torch tensor) to get
    `b x dimension` features, differentiable in the means and durations: per such skill its
    means, its times and its path's indicators (see the module); other skills' parameters pass
    through unchanged.
    """

    def __init__(self, space: SearchSpace, models: dict[str, HSMM]) -> None:
        self.bounds = np.asarray(space.bounds, dtype=float)
        self.skills: list[SkillSlots] = []
        for (skill, part), start in zip(space.parts.items(), space.starts.values()):
            model = models[skill]
            transmat = np.asarray(model.transmat_, dtype=float)
            duration_means = np.asarray(model.duration_means_, dtype=float)
            self.skills.append(SkillSlots(start, part, transmat, int(np.argmax(model.startprob_)), duration_means))

    @cached_property
    def time_scales(self) -> list[TimeScale | None]:
        """Per skill, its varying times and their ranges (None for a skill of means alone)."""
        from torch.quasirandom import SobolEngine

        reference = self._task_units(SobolEngine(self.bounds.shape[1], scramble=True, seed=0).draw(SCALE_POINTS).double())
        return [self._time_scale(skill, reference) if skill.modelled else None for skill in self.skills]

    @property
    def dimension(self) -> int:
        """How many features a point has."""
        return sum(self._skill_dimension(skill, scale) for skill, scale in zip(self.skills, self.time_scales))

    def _task_units(self, unit: torch.Tensor) -> torch.Tensor:
        import torch

        bounds = torch.as_tensor(self.bounds, dtype=unit.dtype)
        return bounds[0] + unit * (bounds[1] - bounds[0])

    def _time_scale(self, skill: SkillSlots, points: torch.Tensor) -> TimeScale:
        """Times only grow with each duration, so on each path sampled by `points` their range
        is that of the durations at their lower and at their upper bounds."""
        positions = skill.positions(points.numpy())
        on_path = np.concatenate([positions >= 0, np.ones((len(points), 1), dtype=bool)], axis=1)
        durations = skill.start + skill.space.duration_columns
        extremes = []
        for side, missing in ((0, np.inf), (1, -np.inf)):  # a state on no sampled path: no range
            at_bound = points.clone()
            at_bound[:, durations] = points.new_tensor(self.bounds[side, durations])
            extremes.append(np.where(on_path, skill.times(at_bound, positions).numpy(), missing))
        low, high = extremes[0].min(axis=0), extremes[1].max(axis=0)
        columns = np.flatnonzero(np.isfinite(low) & (high - low > 1e-9))
        return TimeScale(columns, low[columns], high[columns])

    @staticmethod
    def _skill_dimension(skill: SkillSlots, scale: TimeScale | None) -> int:
        if scale is None:
            return skill.space.dimension
        return len(skill.space.mean_slots) + len(scale.columns) + (skill.states if skill.space.transition_slots else 0)

    def __call__(self, unit: torch.Tensor) -> torch.Tensor:
        import torch

        shape = unit.shape
        unit = unit.reshape(-1, shape[-1])
        points = self._task_units(unit)
        columns = []
        for skill, scale in zip(self.skills, self.time_scales):
            own = unit[:, skill.start : skill.start + skill.space.dimension]
            if scale is None:
                columns.append(own)
                continue
            positions = skill.positions(points.detach().numpy())
            visited = torch.as_tensor(positions >= 0, dtype=unit.dtype)
            columns.append(self._means(skill, own, visited))
            columns.append(self._times(skill, scale, points, positions, visited))
            if skill.space.transition_slots:
                columns.append(visited)
        return torch.cat(columns, dim=-1).reshape(*shape[:-1], -1)

    @staticmethod
    def _means(skill: SkillSlots, own: torch.Tensor, visited: torch.Tensor) -> torch.Tensor:
        """`b x m` the means in the unit cube, those of skipped states at `SKIPPED`."""
        import torch

        groups = [list(group) for group, _ in skill.space.mean_slots]
        if not groups:
            return own[:, :0]
        on_path = torch.stack([visited[:, group].amax(dim=-1) for group in groups], dim=-1)
        return on_path * own[:, : len(groups)] + (1 - on_path) * SKIPPED

    @staticmethod
    def _times(skill: SkillSlots, scale: TimeScale, points: torch.Tensor, positions: np.ndarray, visited: torch.Tensor) -> torch.Tensor:
        """`b x t` the varying times scaled to their range, those of skipped states at `SKIPPED`."""
        import torch

        times = skill.times(points, positions)[:, scale.columns]
        scaled = (times - torch.as_tensor(scale.low, dtype=times.dtype)) / torch.as_tensor(scale.high - scale.low, dtype=times.dtype)
        on_path = torch.cat([visited, torch.ones_like(visited[:, :1])], dim=-1)[:, scale.columns]
        return on_path * scaled + (1 - on_path) * SKIPPED


def path_features(space: SearchSpace, models: dict[str, HSMM]) -> PathFeatures | None:
    """The features of method `stl`'s GP for `space`, or None when no skill's durations or
    transition entries are optimised (the GP then sees the points themselves)."""
    features = PathFeatures(space, models)  # cheap: the times' ranges are found on first use
    return features if any(skill.modelled for skill in features.skills) else None
