"""What the GP of method `stl` sees of a point: the skill as it will be executed.

A skill's transition entries act on its execution only through the state path they select
(`HSMM.nominal_path`: from the most likely first state, the most likely successor of each), and
the means and durations of the states off that path do not act at all. So a part's robustness
is a step function of the transition entries, flat between the switches of a row's largest
entry, and indifferent to the parameters of skipped states: a GP on the raw point must learn
steps and irrelevant directions from a few trials. `PathFeatures` gives it instead, per skill,
one indicator per state (on the path or not), and the means and durations of the states on the
path (those of skipped states are set to the middle of their range). Two points that execute
the same are then the same input, and points on different paths differ by the states they
visit differently.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.space import ParameterSpace, SearchSpace

SKIPPED = 0.5  # a skipped state's mean or duration, in the unit cube


@dataclass(frozen=True)
class SkillSlots:
    """Where one skill's parameters sit in a point, and what its transitions start from.

    Attributes:
        start: index of the skill's first parameter in the point.
        space: the skill's parameter space.
        transmat: `K x K` the model's transition matrix (as stored: `ParameterSpace.apply`
            writes the point's entries into it before renormalising).
        first_state: the most likely first state.
    """

    start: int
    space: ParameterSpace
    transmat: np.ndarray
    first_state: int

    def visited(self, points: np.ndarray) -> np.ndarray:
        """`b x K` booleans: the states on each of `b x d` points' path (points in the task's
        units; the same path as `space.apply(model, point).nominal_path()`)."""
        space, count = self.space, len(points)
        K = len(self.transmat)
        transition_columns = self.start + len(space.mean_slots) + len(space.duration_slots) + np.arange(len(space.transition_slots))
        transition_bounds = (space.lower[-len(space.transition_slots) :], space.upper[-len(space.transition_slots) :])
        transmat = np.clip(np.broadcast_to(self.transmat, (count, K, K)).copy(), 0.0, None)
        for column, (source, target), low, high in zip(transition_columns, space.transition_slots, *transition_bounds):
            transmat[:, source, target] = np.clip(np.clip(points[:, column], low, high), 0.0, None)
        visited = np.zeros((count, K), dtype=bool)
        state = np.full(count, self.first_state)
        walking = np.ones(count, dtype=bool)
        rows = np.arange(count)
        visited[rows, state] = True
        for _ in range(K):
            outgoing = transmat[rows, state]  # b x K
            successor = np.argmax(outgoing, axis=1)  # ties to the lower state, as nominal_path
            walking &= (outgoing.sum(axis=1) > 0) & ~visited[rows, successor]
            visited[rows[walking], successor[walking]] = True
            state = np.where(walking, successor, state)
        return visited


class PathFeatures:
    """The GP inputs of points of a `SearchSpace` whose skills have transition entries.

    Call with `b x d` points in the unit cube of the space's bounds (a torch tensor) to get
    `b x f` features, differentiable in the means and durations of the states on the path:
    per skill its means and durations (those of skipped states at `SKIPPED`), then one
    indicator per state; skills without transition entries pass through unchanged.
    """

    def __init__(self, space: SearchSpace, models: dict[str, HSMM]) -> None:
        self.bounds = space.bounds
        self.skills: list[SkillSlots] = []
        start = 0
        for skill, part in space.parts.items():
            model = models[skill]
            self.skills.append(SkillSlots(start, part, np.asarray(model.transmat_, dtype=float), int(np.argmax(model.startprob_))))
            start += part.dimension
        self.dimension = sum(self._width(skill) for skill in self.skills)

    @staticmethod
    def _width(skill: SkillSlots) -> int:
        space = skill.space
        if not space.transition_slots:
            return space.dimension
        return len(space.mean_slots) + len(space.duration_slots) + len(skill.transmat)

    def __call__(self, unit):
        import torch

        points = self.bounds[0] + unit.detach().numpy() * (self.bounds[1] - self.bounds[0])
        columns = []
        for skill in self.skills:
            space, start = skill.space, skill.start
            own = unit[..., start : start + space.dimension]
            if not space.transition_slots:
                columns.append(own)
                continue
            visited = torch.as_tensor(skill.visited(points.reshape(-1, points.shape[-1])).reshape(*unit.shape[:-1], -1), dtype=unit.dtype)
            states = [group for group, _ in space.mean_slots] + [(state,) for state in space.duration_slots]
            on_path = torch.stack([visited[..., list(group)].amax(dim=-1) for group in states], dim=-1)  # ... x (means + durations)
            kept = own[..., : len(states)]
            columns += [on_path * kept + (1 - on_path) * SKIPPED, visited]
        return torch.cat(columns, dim=-1)


def path_features(space: SearchSpace, models: dict[str, HSMM]) -> PathFeatures | None:
    """The features of method `stl`'s GP for `space`, or None when no skill's transition
    entries are optimised (the GP then sees the points themselves)."""
    if not any(part.transition_slots for part in space.parts.values()):
        return None
    return PathFeatures(space, models)
