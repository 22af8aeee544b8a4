"""Parameter spaces: which model parameters the optimiser moves, their bounds, and how a point
becomes a model.

A point `x` is a `d` vector, ordered: the selected state means (state by state, coordinate by
coordinate), the selected duration means, then the selected transition entries. Bounds follow
the paper: mean +- beta standard deviations of the state's covariance per coordinate (in the
chosen frame for a TP-HSMM, whose means move in that frame; states
moved `together` share one position parameter per coordinate, bounded by the smallest of
their standard deviations), duration
mean +- width duration standard deviations (never below one sample period), and [0, 1] for
transition entries, whose rows are renormalised before retrieval.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.settings import SINGLE_SKILL, MeanParameters, Parameters
from stl_lfd.rotations import ROTATION_COLUMNS


@dataclass(frozen=True)
class ParameterSpace:
    """The optimised parameters of one model.

    Attributes:
        names: `d` readable names, such as `mean[2].x`, `duration[3]`, `transition[2->3]` (1-based).
        lower, upper: `d` bounds.
        initial: `d` values of the unmodified model (inside the bounds).
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    initial: np.ndarray
    mean_slots: tuple[tuple[tuple[int, ...], int], ...]
    duration_slots: tuple[int, ...]
    transition_slots: tuple[tuple[int, int], ...]

    @property
    def dimension(self) -> int:
        return len(self.names)

    @property
    def bounds(self) -> np.ndarray:
        """`2 x d`: lower bounds, then upper bounds (BoTorch's convention)."""
        return np.vstack([self.lower, self.upper])

    @property
    def duration_columns(self) -> np.ndarray:
        """Where `duration_slots` sit in a point: after the means."""
        return len(self.mean_slots) + np.arange(len(self.duration_slots))

    @property
    def transition_columns(self) -> np.ndarray:
        """Where `transition_slots` sit in a point: after the means and durations."""
        return len(self.mean_slots) + len(self.duration_slots) + np.arange(len(self.transition_slots))

    def apply(self, model: HSMM, x: np.ndarray) -> HSMM:
        """A copy of `model` with the parameters of point `x` (`d`), clipped to the bounds."""
        x = np.clip(np.asarray(x, dtype=float), self.lower, self.upper)
        changed = copy.deepcopy(model)
        changed.means_ = np.array(model.means_, dtype=float)
        changed.duration_means_ = np.array(model.duration_means_, dtype=float)
        changed.transmat_ = np.array(model.transmat_, dtype=float)
        values = iter(x)
        for group, coordinate in self.mean_slots:
            shift = next(values) - model.means_[group[0], coordinate]
            for state in group:  # a group moves together: the first state's position, the others by as much
                changed.means_[state, coordinate] = model.means_[state, coordinate] + shift
        for state in self.duration_slots:
            changed.duration_means_[state] = next(values)
        for source, target in self.transition_slots:
            changed.transmat_[source, target] = next(values)
        if self.transition_slots:
            changed.transmat_ = changed.normalized_transmat()
        return changed

    def as_dict(self, x: np.ndarray) -> dict[str, float]:
        return {name: float(value) for name, value in zip(self.names, x)}


def build_space(model: HSMM, parameters: Parameters, source: Path | str = "task", where: str = "parameters") -> ParameterSpace:
    """The space that `parameters` (from a task file, at key `where`) selects on `model`."""
    K = model.n_states
    names: list[str] = []
    lower: list[float] = []
    upper: list[float] = []
    initial: list[float] = []

    def add(name: str, value: float, low: float, high: float) -> None:
        names.append(name)
        initial.append(value)
        lower.append(low)
        upper.append(high)

    means = parameters.means
    mean_slots = []
    states = _states(means.components, K, source, f"{where}.means.components")
    groups = [tuple(states)] if means.together else [(state,) for state in states]
    for group in groups:
        stds = np.min([np.sqrt(np.diag(model.covars_[state])) for state in group], axis=0)
        label = "+".join(str(state + 1) for state in group)
        for name in means.coordinates:
            try:
                coordinate = model.coordinate(name, means.frame)
            except ModelError as error:
                key = f"{where}.means.frame" if means.frame is not None else f"{where}.means.coordinates"
                raise ConfigError(f"{source}: '{key}': {error}") from None
            value = model.means_[group[0], coordinate]
            low, high = _mean_bounds(means, name, value, stds[coordinate])
            frame = f"{means.frame}." if means.frame is not None else ""
            kind = "orient" if name in ROTATION_COLUMNS else "mean"
            add(f"{kind}[{label}].{frame}{name}", value, low, high)
            mean_slots.append((group, coordinate))

    durations = parameters.durations
    duration_slots = []
    for state in _states(durations.components, K, source, f"{where}.durations.components"):
        value, spread = model.duration_means_[state], durations.width * model.duration_stds_[state]
        add(f"duration[{state + 1}]", value, max(value - spread, model.sample_period_), value + spread)
        duration_slots.append(state)

    transition_slots = transition_entries(K, parameters.transitions)
    probabilities = model.normalized_transmat()
    for source_state, target in transition_slots:
        add(f"transition[{source_state + 1}->{target + 1}]", probabilities[source_state, target], 0.0, 1.0)

    return ParameterSpace(
        names=tuple(names),
        lower=np.array(lower),
        upper=np.array(upper),
        initial=np.array(initial),
        mean_slots=tuple(mean_slots),
        duration_slots=tuple(duration_slots),
        transition_slots=tuple(transition_slots),
    )


def _mean_bounds(means: MeanParameters, coordinate: str, value: float, std: float) -> tuple[float, float]:
    """A mean's bounds: `means.offset` around it for a position, else `beta` standard deviations."""
    if means.offset is not None and coordinate not in ROTATION_COLUMNS:
        return value + means.offset[0], value + means.offset[1]
    return value - means.beta * std, value + means.beta * std


def transition_entries(K: int, kind: str) -> list[tuple[int, int]]:
    """(from, to) entries (0-based): `full` every off-diagonal one, `band` the paper's reduced
    set of successors i+1 and i+2, `none` nothing."""
    if kind == "none":
        return []
    if kind == "full":
        return [(i, j) for i in range(K) for j in range(K) if i != j]
    return [(i, j) for i in range(K) for j in (i + 1, i + 2) if j < K]


def _states(components: tuple[int, ...] | str, K: int, source: Path | str, key: str) -> list[int]:
    if components == "all":
        return list(range(K))
    for state in components:
        if state > K:
            raise ConfigError(f"{source}: '{key}' names state {state}, but the model has {K} states (numbered 1-{K})")
    return [state - 1 for state in components]


@dataclass(frozen=True)
class SearchSpace:
    """The optimised parameters of all skills of a task: the skills' spaces side by side.

    A point is the concatenation of each skill's point, in the order of `parts`; names are
    prefixed with the skill (`pick.duration[2]`) unless the task has a single skill.
    """

    parts: dict[str, ParameterSpace]

    @property
    def names(self) -> tuple[str, ...]:
        if list(self.parts) == [SINGLE_SKILL]:
            return self.parts[SINGLE_SKILL].names
        return tuple(f"{skill}.{name}" for skill, part in self.parts.items() for name in part.names)

    @property
    def lower(self) -> np.ndarray:
        return np.concatenate([part.lower for part in self.parts.values()])

    @property
    def upper(self) -> np.ndarray:
        return np.concatenate([part.upper for part in self.parts.values()])

    @property
    def initial(self) -> np.ndarray:
        return np.concatenate([part.initial for part in self.parts.values()])

    @property
    def bounds(self) -> np.ndarray:
        """`2 x d`: lower bounds, then upper bounds."""
        return np.vstack([self.lower, self.upper])

    @property
    def dimension(self) -> int:
        return sum(part.dimension for part in self.parts.values())

    @property
    def starts(self) -> dict[str, int]:
        """Per skill, the index of its first parameter in a point."""
        ends = np.cumsum([part.dimension for part in self.parts.values()])
        return {skill: int(end) - part.dimension for (skill, part), end in zip(self.parts.items(), ends)}

    def apply(self, models: dict[str, HSMM], x: np.ndarray) -> dict[str, HSMM]:
        """The skills' models with the parameters of point `x` (`d`); other skills unchanged."""
        adapted = dict(models)
        for (skill, part), start in zip(self.parts.items(), self.starts.values()):
            adapted[skill] = part.apply(models[skill], np.asarray(x)[start : start + part.dimension])
        return adapted

    def as_dict(self, x: np.ndarray) -> dict[str, float]:
        return {name: float(value) for name, value in zip(self.names, x)}


def build_search_space(models: dict[str, HSMM], parameters: dict[str, Parameters], source: Path | str = "task") -> SearchSpace:
    """The space of a task: `parameters` (skill -> selection) applied to `models` (skill -> model)."""
    return SearchSpace({skill: build_space(models[skill], selection, source, _key(skill)) for skill, selection in parameters.items()})


def _key(skill: str) -> str:
    """Where a skill's selection stands in a task file."""
    return "parameters" if skill == SINGLE_SKILL else f"parameters.{skill}"
