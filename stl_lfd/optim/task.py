"""Task files: what to optimise, against which spec, how to execute it, with what budget.

A task file is YAML (see `configs/phi1.yaml`); paths in it are relative to the file. States
are numbered from 1, as `stlopt learn` prints them. Every key is checked: unknown keys, wrong
types and bounds that make no sense are `ConfigError`s naming the file and the key.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterator

from stl_lfd.choices import BACKENDS, METHODS, SEMANTICS
from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_PLACEMENTS, MAX_SEED, MAX_STATES, MAX_TRIALS, MAX_WORKERS, samples_problem
from stl_lfd.poses import Pose
from stl_lfd.sim.command import DEFAULT_TIMEOUT, Command
from stl_lfd.yamlfile import check_keys, integer, number, read_yaml, shown

SINGLE_SKILL = "skill"  # the name of the one skill of a task without a behaviour
TRANSITIONS = ("none", "band", "full")
COORDINATES = ("x", "y", "z")


@dataclass(frozen=True)
class MeanParameters:
    """State means to optimise: `components` (1-based), `coordinates`, bounds mean +- beta std;
    `together` moves the components by one shared offset (e.g. an approach and a final pose);
    `frame` names the frame of a TP-HSMM in which they move (bounds from that frame's
    covariance)."""

    components: tuple[int, ...] = ()
    coordinates: tuple[str, ...] = COORDINATES
    beta: float = 2.0
    together: bool = False
    frame: str | None = None  # for a TP-HSMM: the frame the means move in

    def __post_init__(self) -> None:
        _check_states(self.components, "means.components")
        unknown = [coordinate for coordinate in self.coordinates if coordinate not in COORDINATES]
        if unknown or not self.coordinates:
            raise ConfigError(f"'means.coordinates' may hold x, y, z (got {shown(list(self.coordinates))})")
        if not self.beta > 0:
            raise ConfigError(f"'means.beta' must be positive (got {self.beta})")


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
    proposed together (methods plan, stl and random)."""

    method: str = "plan"
    initial: int = 8
    trials: int = 32
    seed: int = 0
    xi: float = 0.1
    workers: int = 1

    def __post_init__(self) -> None:
        """Refuse settings that make no sense, from a task file, the command line or Python."""
        if self.method not in METHODS:
            raise ConfigError(f"'optimizer.method' must be one of {', '.join(METHODS)} (got {shown(self.method)})")
        if self.initial < 1 or self.trials < 1:
            raise ConfigError("'optimizer.initial' and 'optimizer.trials' must be at least 1")
        if self.initial > self.trials:
            raise ConfigError(f"'optimizer.initial' ({self.initial}) exceeds 'optimizer.trials' ({self.trials}), the total number of trials")
        if self.trials > MAX_TRIALS:
            raise ConfigError(f"'optimizer.trials' ({self.trials}) is above the limit of {MAX_TRIALS} trials")
        if not 0 <= self.seed <= MAX_SEED:
            raise ConfigError(f"'optimizer.seed' must be from 0 to {MAX_SEED} (got {shown(self.seed)})")
        if not self.xi >= 0:
            raise ConfigError(f"'optimizer.xi' must be at least 0 (got {self.xi})")
        if not 1 <= self.workers <= MAX_WORKERS:
            raise ConfigError(f"'optimizer.workers' must be from 1 to {MAX_WORKERS} (got {shown(self.workers)})")
        if self.workers > 1 and self.method in ("pi", "logei"):
            raise ConfigError(f"method {self.method} proposes one trial at a time; parallel trials ('optimizer.workers' > 1) need method stl, plan or random")


@dataclass(frozen=True)
class Task:
    """A validated task file; paths are absolute or relative to the working directory.

    The skills come from `demos` (learned with `states` states), a `model` file, or a
    `behaviour` file (several skills and gripper actions). `parameters` maps each skill name
    (`skill` for a single skill) to what is optimised in it. `placements` lists where the
    scene's object frames stand (frame -> pose, the others at the scene's poses); each trial
    executes once per placement and scores the worst. Empty: the scene as it is.
    """

    name: str
    spec: Path
    model: Path | None
    demos: Path | None
    behaviour: Path | None
    states: int
    scene: str
    backend: str
    semantics: str
    nu: float
    duration: float
    rate: float
    parameters: dict[str, Parameters]
    optimizer: Optimizer
    source: Path
    command: Command | None = None
    placements: tuple[dict[str, Pose], ...] = ()

    def __post_init__(self) -> None:
        if self.backend == "command" and self.command is None:
            raise ConfigError(f"{self.source}: the command backend needs the command that executes a trial ('command' in the task file, or --command)")

    def with_overrides(self, **changes: Any) -> "Task":
        """A copy with command-line overrides (`spec`, `backend`, `command`, `placements`, `seed`, `initial`, `trials`, `method`)."""
        optimizer_keys = {"seed", "initial", "trials", "method", "workers"}
        with _located(self.source):
            optimizer = replace(self.optimizer, **{k: v for k, v in changes.items() if k in optimizer_keys and v is not None})
        return replace(self, optimizer=optimizer, **{k: v for k, v in changes.items() if k not in optimizer_keys and v is not None})

    def to_yaml_dict(self) -> dict[str, Any]:
        """The task as it is used, in the task-file format (paths made absolute)."""
        data: dict[str, Any] = {"name": self.name, "spec": str(self.spec.resolve())}
        if self.model is not None:
            data["model"] = str(self.model.resolve())
        if self.behaviour is not None:
            data["behaviour"] = str(self.behaviour.resolve())
        if self.demos is not None:
            data["demos"] = str(self.demos.resolve())
            data["states"] = self.states
        data.update(scene=self.scene, backend=self.backend, semantics=self.semantics, nu=self.nu, duration=self.duration, rate=self.rate)
        if self.command is not None:
            data["command"] = self.command.to_dict()
        if self.placements:
            data["placements"] = placements_to_yaml(self.placements)
        blocks = {name: _parameters_to_yaml(parameters) for name, parameters in self.parameters.items()}
        data["parameters"] = blocks[SINGLE_SKILL] if self.behaviour is None else blocks
        opt = self.optimizer
        data["optimizer"] = {"method": opt.method, "initial": opt.initial, "trials": opt.trials, "seed": opt.seed, "xi": opt.xi}
        if opt.workers > 1:  # absent for one worker, so that the record of older runs still matches
            data["optimizer"]["workers"] = opt.workers
        return data


TOP_KEYS = (
    "name",
    "spec",
    "model",
    "demos",
    "behaviour",
    "states",
    "scene",
    "backend",
    "command",
    "semantics",
    "nu",
    "duration",
    "rate",
    "parameters",
    "optimizer",
    "place",
    "placements",
)


def placements_to_yaml(placements: tuple[dict[str, Pose], ...]) -> list[dict[str, Any]]:
    """The task-file form of `placements`: a list of frame -> {position, yaw}."""
    return [{name: pose.as_dict() for name, pose in placement.items()} for placement in placements]


def _parameters_to_yaml(parameters: Parameters) -> dict[str, Any]:
    """The task-file form of a selection; blocks that select nothing are left out."""
    means, durations = parameters.means, parameters.durations
    block: dict[str, Any] = {}
    if means.components:
        block["means"] = {"components": list(means.components), "coordinates": list(means.coordinates), "beta": means.beta, "together": means.together}
        if means.frame is not None:
            block["means"]["frame"] = means.frame
    if durations.components:
        components = durations.components if isinstance(durations.components, str) else list(durations.components)
        block["durations"] = {"components": components, "width": durations.width}
    block["transitions"] = parameters.transitions
    return block


def load_task(path: str | Path) -> Task:
    """Read and validate a task file."""
    return parse_task(read_yaml(path), Path(path))


def parse_task(data: dict[str, Any], path: Path) -> Task:
    """Validate the mapping of a task file; relative paths in it start at `path`'s folder, and
    errors name `path` (a sweep parses task files with its overrides merged in this way)."""
    check_keys(data, TOP_KEYS, path, required=("spec", "duration"))
    if sum(key in data for key in ("model", "demos", "behaviour")) != 1:
        raise ConfigError(f"{path}: give exactly one of 'model' (a model file), 'demos' (a folder to learn from) or 'behaviour' (a behaviour file)")
    base = path.parent
    behaviour = _existing(base, data["behaviour"], path, "behaviour") if "behaviour" in data else None
    semantics = _choice(data.get("semantics", "new"), SEMANTICS, path, "semantics")
    backend = _choice(data.get("backend", "pybullet"), BACKENDS, path, "backend")
    task = Task(
        name=_name(data.get("name", path.stem), path),
        spec=_existing(base, data["spec"], path, "spec"),
        model=_existing(base, data["model"], path, "model") if "model" in data else None,
        demos=_existing(base, data["demos"], path, "demos") if "demos" in data else None,
        behaviour=behaviour,
        states=integer(data.get("states", 6), path, "states", minimum=1, maximum=MAX_STATES),
        scene=str(data.get("scene", _behaviour_scene(behaviour) if behaviour else "free_space")),
        backend=backend,
        semantics=semantics,
        nu=number(data.get("nu", 1.0), path, "nu", positive=True),
        duration=number(data["duration"], path, "duration", positive=True),
        rate=number(data.get("rate", 100.0), path, "rate", positive=True),
        parameters=_skill_parameters(data.get("parameters", {}), path, behaviour),
        optimizer=_optimizer(data.get("optimizer", {}), path),
        source=path,
        command=_command(data["command"], path) if "command" in data else None,
    )
    if "place" in data or "placements" in data:
        task = replace(task, placements=_placements(data, path, task.scene))
    problem = samples_problem(task.duration, task.rate)
    if problem:
        raise ConfigError(f"{path}: 'duration' and 'rate': {problem}")
    return task


@contextmanager
def _located(path: Path) -> Iterator[None]:
    """Prefix the ConfigErrors raised inside with the file they are about."""
    try:
        yield
    except ConfigError as error:
        raise ConfigError(f"{path}: {error}") from None


def _behaviour_scene(behaviour: Path) -> str:
    from stl_lfd.skill.behaviour import load_behaviour

    return load_behaviour(behaviour).scene


def _placements(data: dict[str, Any], path: Path, scene_name: str) -> tuple[dict[str, Pose], ...]:
    """`place: {FRAME: POSE}` (one placement) or `placements: [{FRAME: POSE}, ...]`."""
    from stl_lfd.sim import load_scene

    if "place" in data and "placements" in data:
        raise ConfigError(f"{path}: give 'place' (one placement) or 'placements' (several), not both")
    scene = load_scene(scene_name)
    if "place" in data:
        return (scene.placement_from_yaml(data["place"], path, "place"),)
    items = data["placements"]
    if not isinstance(items, list) or not items or len(items) > MAX_PLACEMENTS:
        raise ConfigError(f"{path}: 'placements' must be a list of 1 to {MAX_PLACEMENTS} placements (each mapping frames to poses)")
    return tuple(scene.placement_from_yaml(item, path, f"placements[{index}]") for index, item in enumerate(items))


def _skill_parameters(data: Any, path: Path, behaviour: Path | None) -> dict[str, Parameters]:
    """`parameters` of a single-skill task, or per skill of a behaviour."""
    if behaviour is None:
        return {SINGLE_SKILL: _parameters(data, path, "parameters")}
    from stl_lfd.skill.behaviour import load_behaviour

    skills = [step.name for step in load_behaviour(behaviour).skills]
    check_keys(data, skills, path, "parameters")
    blocks = {name: _parameters(block, path, f"parameters.{name}") for name, block in data.items()}
    if not blocks:
        raise ConfigError(f"{path}: 'parameters' selects nothing to optimise (name skills of the behaviour: {', '.join(skills)})")
    return blocks


def _parameters(data: Any, path: Path, where: str) -> Parameters:
    check_keys(data, ("means", "durations", "transitions"), path, where)
    means, durations = MeanParameters(), DurationParameters()
    if "means" in data:
        item = check_keys(data["means"], ("components", "coordinates", "beta", "together", "frame"), path, f"{where}.means", required=("components",))
        if "frame" in item and not isinstance(item["frame"], str):
            raise ConfigError(f"{path}: '{where}.means.frame' must be the name of one of the model's frames (got {shown(item['frame'])})")
        if not isinstance(item.get("together", False), bool):
            raise ConfigError(f"{path}: '{where}.means.together' must be true or false")
        coordinates = tuple(item.get("coordinates", COORDINATES))
        for coordinate in coordinates:
            if coordinate not in COORDINATES:
                raise ConfigError(f"{path}: '{where}.means.coordinates' may hold x, y, z (got {shown(coordinate)})")
        means = MeanParameters(
            components=_components(item["components"], path, f"{where}.means.components", allow_all=False),
            coordinates=coordinates,
            beta=number(item.get("beta", 2.0), path, f"{where}.means.beta", positive=True),
            together=item.get("together", False),
            frame=item.get("frame"),
        )
    if "durations" in data:
        item = check_keys(data["durations"], ("components", "width"), path, f"{where}.durations", required=("components",))
        durations = DurationParameters(
            components=_components(item["components"], path, f"{where}.durations.components", allow_all=True),
            width=number(item.get("width", 1.0), path, f"{where}.durations.width", positive=True),
        )
    transitions = _choice(data.get("transitions", "none"), TRANSITIONS, path, f"{where}.transitions")
    if not means.components and not durations.components and transitions == "none":
        raise ConfigError(f"{path}: '{where}' selects nothing to optimise")
    with _located(path):
        return Parameters(means, durations, transitions)


def _command(data: Any, path: Path) -> Command:
    """`command: "..."`, or a block with `run` (a string or an argument list), `timeout`,
    `shell` and `cwd` (default: the task file's folder, where relative paths in it start)."""
    if isinstance(data, (str, list)):
        data = {"run": data}
    item = check_keys(data, ("run", "timeout", "shell", "cwd"), path, "command", required=("run",))
    run = item["run"]
    if not (isinstance(run, str) or (isinstance(run, list) and all(isinstance(argument, (str, int, float)) for argument in run))):
        raise ConfigError(f"{path}: 'command.run' must be a command line or a list of arguments (got {shown(run)})")
    shell = item.get("shell", False)
    if not isinstance(shell, bool):
        raise ConfigError(f"{path}: 'command.shell' must be true or false")
    cwd = _existing(path.parent, item["cwd"], path, "command.cwd") if "cwd" in item else path.parent
    timeout = number(item.get("timeout", DEFAULT_TIMEOUT), path, "command.timeout", positive=True)
    with _located(path):
        return Command.parse(run, timeout, shell, cwd.resolve())


def _optimizer(data: Any, path: Path) -> Optimizer:
    check_keys(data, ("method", "initial", "trials", "seed", "xi", "workers"), path, "optimizer")
    defaults = Optimizer()
    settings = dict(
        method=_choice(data.get("method", defaults.method), METHODS, path, "optimizer.method"),
        initial=integer(data.get("initial", defaults.initial), path, "optimizer.initial", minimum=1),
        trials=integer(data.get("trials", defaults.trials), path, "optimizer.trials", minimum=1),
        seed=integer(data.get("seed", defaults.seed), path, "optimizer.seed", minimum=0, maximum=MAX_SEED),
        xi=number(data.get("xi", defaults.xi), path, "optimizer.xi", minimum=0.0),
        workers=integer(data.get("workers", defaults.workers), path, "optimizer.workers", minimum=1, maximum=MAX_WORKERS),
    )
    with _located(path):
        return Optimizer(**settings)


def _components(value: Any, path: Path, key: str, allow_all: bool) -> tuple[int, ...] | str:
    if allow_all and value == "all":
        return "all"
    if not isinstance(value, list) or not value:
        expected = "a non-empty list of state numbers" + (" or 'all'" if allow_all else "")
        raise ConfigError(f"{path}: '{key}' must be {expected} (got {shown(value)})")
    numbers = tuple(integer(item, path, key, minimum=1) for item in value)
    if len(set(numbers)) != len(numbers):
        raise ConfigError(f"{path}: '{key}' lists a state twice ({list(numbers)})")
    return numbers


def _name(value: Any, path: Path) -> str:
    """The task's name: it names the default run directory, `runs/<name>`, so one plain word."""
    if not isinstance(value, (str, int)) or not str(value).strip() or "/" in str(value) or str(value) in (".", ".."):
        raise ConfigError(f"{path}: 'name' must be a plain name without '/' (got {shown(value)})")
    return str(value)


def _choice(value: Any, choices: tuple[str, ...], path: Path, key: str) -> str:
    if value not in choices:
        raise ConfigError(f"{path}: '{key}' must be one of {', '.join(choices)} (got {shown(value)})")
    return value


def _existing(base: Path, value: Any, path: Path, key: str) -> Path:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{path}: '{key}' must be a path (got {shown(value)})")
    resolved = Path(value) if Path(value).is_absolute() else base / value
    if not resolved.exists():
        raise ConfigError(f"{path}: '{key}' names {value}, which does not exist (paths are relative to the task file)")
    return resolved
