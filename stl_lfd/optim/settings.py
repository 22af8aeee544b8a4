"""What an optimisation moves and how it searches: the parameters selected in each skill, and
the optimiser's settings (`Optimizer`). Each validates itself when made, from a task file, the
command line or Python; the functions at the end read them from a task file's YAML."""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping

from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_SEED, MAX_TRIALS, MAX_WORKERS
from stl_lfd.optim.method_registry import method_class, method_names, settings_class, tuned_method_names
from stl_lfd.rotations import ROTATION_COLUMNS
from stl_lfd.yamlfile import check_keys, integer, number, settings_from_yaml, settings_to_yaml, shown, vector

SINGLE_SKILL = "skill"  # the name of the one skill of a task without a behaviour
TRANSITIONS = ("none", "band", "full")
POSITION_COORDINATES = ("x", "y", "z")
COORDINATES = POSITION_COORDINATES + ROTATION_COLUMNS  # a skill with orientation also moves its rotation vector


@dataclass(frozen=True)
class MeanParameters:
    """State means to optimise: `components` (1-based), `coordinates`, bounds mean +- beta std;
    `together` moves the components by one shared offset (e.g. an approach and a final pose);
    `frame` names the frame of a TP-HSMM in which they move (bounds from that frame's
    covariance). For a skill with orientation, `rx, ry, rz` move the state's mean orientation
    (its rotation vector relative to the skill's reference orientation, in radians), bounded by
    the state's orientation covariance. `offset` (m, `(lower, upper)`) bounds the positions
    by that much around the mean instead of `beta` standard deviations (which still bounds
    the orientation coordinates)."""

    components: tuple[int, ...] = ()
    coordinates: tuple[str, ...] = POSITION_COORDINATES
    beta: float = 2.0
    together: bool = False
    frame: str | None = None  # for a TP-HSMM: the frame the means move in
    offset: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        _check_states(self.components, "means.components")
        unknown = [coordinate for coordinate in self.coordinates if coordinate not in COORDINATES]
        if unknown or not self.coordinates:
            raise ConfigError(f"'means.coordinates' may hold {', '.join(COORDINATES)} (got {shown(list(self.coordinates))})")
        if not self.beta > 0:
            raise ConfigError(f"'means.beta' must be positive (got {self.beta})")
        if self.offset is not None and not (len(self.offset) == 2 and self.offset[0] <= 0 <= self.offset[1] and self.offset[0] < self.offset[1]):
            raise ConfigError(f"'means.offset' must be [lower, upper] in metres with lower <= 0 <= upper, lower < upper (got {shown(list(self.offset))})")


@dataclass(frozen=True)
class DurationParameters:
    """Duration means to optimise (1-based states, or all), bounds mean +- width std."""

    components: tuple[int, ...] | str = ()
    width: float = 1.0

    def __post_init__(self) -> None:
        if self.components != "all":
            _check_states(self.components, "durations.components")
        if not self.width > 0:
            raise ConfigError(f"'durations.width' must be positive (got {self.width})")


@dataclass(frozen=True)
class Parameters:
    """What moves in one skill: state means, duration means, transitions (`none`, `band`, `full`)."""

    means: MeanParameters = field(default_factory=MeanParameters)
    durations: DurationParameters = field(default_factory=DurationParameters)
    transitions: str = "none"

    def __post_init__(self) -> None:
        if self.transitions not in TRANSITIONS:
            raise ConfigError(f"'transitions' must be one of {', '.join(TRANSITIONS)} (got {shown(self.transitions)})")
        if not self.means.components and not self.durations.components and self.transitions == "none":
            raise ConfigError("the parameters select nothing to optimise")


def _check_states(components: tuple[int, ...], key: str) -> None:
    """1-based state numbers, each once (whether they exist is checked against the model)."""
    if any(isinstance(state, bool) or not isinstance(state, int) or state < 1 for state in components):
        raise ConfigError(f"'{key}' must hold state numbers from 1 (got {shown(list(components))})")
    if len(set(components)) != len(components):
        raise ConfigError(f"'{key}' lists a state twice ({list(components)})")


@dataclass(frozen=True)
class Optimizer:
    """Algorithm 1's budget: `initial` (M) initial trials (scrambled Sobol points; with method
    `plan`, chosen on their plans), then `method` until `trials` (N). `plan` (composite BO on
    the spec's parts with each part's plan as its prior) is the default; `stl` is the same
    without plans; `pi` is the paper's algorithm. `workers` trials run at once, each batch
    proposed together (methods plan, stl and random). `tuning` maps a method's name to its
    settings (`methods.tuning`); a method not in it keeps its defaults."""

    method: str = "plan"
    initial: int = 8
    trials: int = 32
    seed: int = 0
    workers: int = 1
    tuning: Mapping[str, Any] = field(default_factory=dict)

    def tuning_for(self, method: str) -> Any:
        """The settings of `method`: those given in `tuning`, or its defaults."""
        return self.tuning[method] if method in self.tuning else settings_class(method)()

    @property
    def initial_choice(self) -> str:
        """How the initial trials are chosen: `chosen on their plans` (method plan) or `Sobol`."""
        return "chosen on their plans" if self.method == "plan" else "Sobol"

    @property
    def phases(self) -> str:
        """The budget and its phases as `stlopt optimize` and the report name them:
        `32 trials: 8 chosen on their plans, then plan`."""
        return f"{self.trials} trials: {self.initial} {self.initial_choice}, then {self.method}"

    def __post_init__(self) -> None:
        """Refuse settings that make no sense, from a task file, the command line or Python."""

        if self.method not in method_names():
            raise ConfigError(f"'optimizer.method' must be one of {', '.join(method_names())} (got {shown(self.method)})")
        if self.initial < 1 or self.trials < 1:
            raise ConfigError("'optimizer.initial' and 'optimizer.trials' must be at least 1")
        if self.initial > self.trials:
            raise ConfigError(f"'optimizer.initial' ({self.initial}) exceeds 'optimizer.trials' ({self.trials}), the total number of trials")
        if self.trials > MAX_TRIALS:
            raise ConfigError(f"'optimizer.trials' ({self.trials}) is above the limit of {MAX_TRIALS} trials")
        if not 0 <= self.seed <= MAX_SEED:
            raise ConfigError(f"'optimizer.seed' must be from 0 to {MAX_SEED} (got {shown(self.seed)})")
        if not 1 <= self.workers <= MAX_WORKERS:
            raise ConfigError(f"'optimizer.workers' must be from 1 to {MAX_WORKERS} (got {shown(self.workers)})")
        if self.workers > 1 and not method_class(self.method).parallel:
            parallel = [name for name in method_names() if method_class(name).parallel]
            raise ConfigError(
                f"method {self.method} proposes one trial at a time; parallel trials ('optimizer.workers' > 1) need method {', '.join(parallel[:-1])} or {parallel[-1]}"
            )
        for name, settings in self.tuning.items():
            if name not in tuned_method_names():
                raise ConfigError(f"'optimizer.{name}': settings are for the methods {', '.join(tuned_method_names())} (got {shown(name)})")
            if not isinstance(settings, settings_class(name)):
                raise ConfigError(f"'optimizer.{name}' must be a {settings_class(name).__name__} (got {shown(settings)})")
        # settings equal to the method's defaults are dropped, so that equal tunings compare equal
        object.__setattr__(self, "tuning", {name: settings for name, settings in self.tuning.items() if settings != settings_class(name)()})


# --- Reading them from a task file's YAML ---


@contextmanager
def located(path: Path) -> Iterator[None]:
    """Prefix the ConfigErrors raised inside with the file they are about."""
    try:
        yield
    except ConfigError as error:
        raise ConfigError(f"{path}: {error}") from None


def parameters_to_yaml(parameters: Parameters) -> dict[str, Any]:
    """The task-file form of a selection; blocks that select nothing are left out."""
    means, durations = parameters.means, parameters.durations
    block: dict[str, Any] = {}
    if means.components:
        block["means"] = {"components": list(means.components), "coordinates": list(means.coordinates), "beta": means.beta, "together": means.together}
        if means.frame is not None:
            block["means"]["frame"] = means.frame
        if means.offset is not None:
            block["means"]["offset"] = list(means.offset)
    if durations.components:
        components = durations.components if isinstance(durations.components, str) else list(durations.components)
        block["durations"] = {"components": components, "width": durations.width}
    block["transitions"] = parameters.transitions
    return block


def parameters_from_yaml(data: Any, path: Path, where: str) -> Parameters:
    check_keys(data, ("means", "durations", "transitions"), path, where)
    means, durations = MeanParameters(), DurationParameters()
    if "means" in data:
        item = check_keys(data["means"], ("components", "coordinates", "beta", "together", "frame", "offset"), path, f"{where}.means", required=("components",))
        if "frame" in item and not isinstance(item["frame"], str):
            raise ConfigError(f"{path}: '{where}.means.frame' must be the name of one of the model's frames (got {shown(item['frame'])})")
        if not isinstance(item.get("together", False), bool):
            raise ConfigError(f"{path}: '{where}.means.together' must be true or false")
        coordinates = tuple(item.get("coordinates", POSITION_COORDINATES))
        for coordinate in coordinates:
            if coordinate not in COORDINATES:
                raise ConfigError(f"{path}: '{where}.means.coordinates' may hold {', '.join(COORDINATES)} (got {shown(coordinate)})")
        means = MeanParameters(
            components=components_from_yaml(item["components"], path, f"{where}.means.components", allow_all=False),
            coordinates=coordinates,
            beta=number(item.get("beta", 2.0), path, f"{where}.means.beta", positive=True),
            together=item.get("together", False),
            frame=item.get("frame"),
            offset=vector(item["offset"], 2, path, f"{where}.means.offset") if "offset" in item else None,
        )
    if "durations" in data:
        item = check_keys(data["durations"], ("components", "width"), path, f"{where}.durations", required=("components",))
        durations = DurationParameters(
            components=components_from_yaml(item["components"], path, f"{where}.durations.components", allow_all=True),
            width=number(item.get("width", 1.0), path, f"{where}.durations.width", positive=True),
        )
    transitions = choice(data.get("transitions", "none"), TRANSITIONS, path, f"{where}.transitions")
    if not means.components and not durations.components and transitions == "none":
        raise ConfigError(f"{path}: '{where}' selects nothing to optimise")
    with located(path):
        return Parameters(means, durations, transitions)


OPTIMIZER_KEYS = ("method", "initial", "trials", "seed", "workers")


def optimizer_from_yaml(data: Any, path: Path) -> Optimizer:
    """The `optimizer` block: the budget, and each method's tuning under the method's name.
    `xi` beside the budget is the older spelling of `pi: {xi: ...}` (runs recorded before
    methods had their own settings)."""
    data = check_keys(_older_spelling(data, path), OPTIMIZER_KEYS + tuned_method_names(), path, "optimizer")
    defaults = Optimizer()
    settings = dict(
        method=choice(data.get("method", defaults.method), method_names(), path, "optimizer.method"),
        initial=integer(data.get("initial", defaults.initial), path, "optimizer.initial", minimum=1),
        trials=integer(data.get("trials", defaults.trials), path, "optimizer.trials", minimum=1),
        seed=integer(data.get("seed", defaults.seed), path, "optimizer.seed", minimum=0, maximum=MAX_SEED),
        workers=integer(data.get("workers", defaults.workers), path, "optimizer.workers", minimum=1, maximum=MAX_WORKERS),
    )
    tuning = {name: settings_from_yaml(settings_class(name)(), data[name], path, f"optimizer.{name}") for name in tuned_method_names() if name in data}
    with located(path):
        return Optimizer(**settings, tuning=tuning)


def recorded_optimizer(data: dict[str, Any], path: Path) -> dict[str, Any]:
    """A run's recorded `optimizer` block as `Task.to_yaml_dict` writes it today: an older
    `xi` moved under `pi`, and each method's settings reduced to those off their defaults."""
    data = dict(_older_spelling(data, path))
    for name in tuned_method_names():
        if name in data:
            defaults = settings_class(name)()
            changed = settings_to_yaml(settings_from_yaml(defaults, data.pop(name), path, f"optimizer.{name}"), defaults)
            data |= {name: changed} if changed else {}
    return data


def _older_spelling(data: Any, path: Path) -> Any:
    """`optimizer.xi` moved into `optimizer.pi.xi`."""
    if not isinstance(data, dict) or "xi" not in data or not isinstance(data.get("pi", {}), dict):
        return data
    if "xi" in data.get("pi", {}):
        raise ConfigError(f"{path}: 'optimizer.xi' and 'optimizer.pi.xi' both set PI's margin; keep 'optimizer.pi.xi'")
    rest = {key: value for key, value in data.items() if key != "xi"}
    return rest | {"pi": data.get("pi", {}) | {"xi": data["xi"]}}


def components_from_yaml(value: Any, path: Path, key: str, allow_all: bool) -> tuple[int, ...] | str:
    if allow_all and value == "all":
        return "all"
    if not isinstance(value, list) or not value:
        expected = "a non-empty list of state numbers" + (" or 'all'" if allow_all else "")
        raise ConfigError(f"{path}: '{key}' must be {expected} (got {shown(value)})")
    numbers = tuple(integer(item, path, key, minimum=1) for item in value)
    if len(set(numbers)) != len(numbers):
        raise ConfigError(f"{path}: '{key}' lists a state twice ({list(numbers)})")
    return numbers


def choice(value: Any, choices: tuple[str, ...], path: Path, key: str) -> str:
    if value not in choices:
        raise ConfigError(f"{path}: '{key}' must be one of {', '.join(choices)} (got {shown(value)})")
    return value
