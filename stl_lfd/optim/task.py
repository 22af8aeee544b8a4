"""Task files: what to optimise, against which spec, how to execute it, with what budget.

A task file is YAML (see `configs/phi1.yaml`); paths in it are relative to the file. States
are numbered from 1, as `stlopt learn` prints them. Every key is checked: unknown keys, wrong
types and bounds that make no sense are `ConfigError`s naming the file and the key.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from stl_lfd.choices import DEFAULT_SEMANTICS, SEMANTICS
from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_PLACEMENTS, MAX_STATES, samples_problem
from stl_lfd.optim.settings import (
    OPTIMIZER_KEYS,
    SINGLE_SKILL,
    Optimizer,
    Parameters,
    choice,
    located,
    optimizer_from_yaml,
    parameters_from_yaml,
    parameters_to_yaml,
)
from stl_lfd.poses import Pose
from stl_lfd.sim.executor import DEFAULT_TIMEOUT, Command
from stl_lfd.sim.registry import DEFAULT_BACKEND, backend_class, backend_names
from stl_lfd.sim.scene_file import scene_reference
from stl_lfd.spelling import spelled
from stl_lfd.yamlfile import check_keys, integer, number, read_yaml, settings_to_yaml, shown


@dataclass(frozen=True)
class Task:
    """A validated task file; paths are absolute or relative to the working directory.

    The skills come from `demos` (learned with `states` states), a `model` file, or a
    `behaviour` file (several skills and gripper actions). `parameters` maps each skill name
    (`skill` for a single skill) to what is optimised in it. `placements` lists where the
    scene's object frames stand (frame -> pose, the others at the scene's poses); each trial
    executes once per placement and scores the worst. Empty: the scene as it is.
    `loaded_behaviour`: the behaviour file as `load_task` read it (a `Behaviour`), so that
    nothing reads it again (`stl_lfd.optim.inputs`).
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
    loaded_behaviour: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        needs_command = backend_class(self.backend).capabilities.needs_command
        if needs_command and self.command is None:
            raise ConfigError(
                f"{self.source}: the {self.backend} backend needs the command that executes a trial ('command' in the task file, or {spelled('command')})"
            )
        if needs_command and len(self.placements) > 1:
            raise ConfigError(f"{self.source}: several placements need a simulated backend (the {self.backend} backend executes one reference per trial)")

    def with_overrides(self, **changes: Any) -> "Task":
        """A copy with the settings of an `Overrides` (`spec`, `backend`, `command`, `placements`,
        `seed`, `initial`, `trials`, `method`, `workers`; None keeps the task's)."""
        return Overrides(**changes).applied_to(self)

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
        blocks = {name: parameters_to_yaml(parameters) for name, parameters in self.parameters.items()}
        data["parameters"] = blocks[SINGLE_SKILL] if self.behaviour is None else blocks
        opt = self.optimizer
        data["optimizer"] = {"method": opt.method, "initial": opt.initial, "trials": opt.trials, "seed": opt.seed}
        if opt.workers > 1:  # absent for one worker, so that the record of older runs still matches
            data["optimizer"]["workers"] = opt.workers
        for method, settings in opt.tuning.items():  # only what differs from the defaults, as for workers
            if changed := settings_to_yaml(settings, type(settings)()):
                data["optimizer"][method] = changed
        return data


@dataclass(frozen=True)
class Overrides:
    """Settings given on top of a task file; None keeps the file's. `trials` (the budget) may
    change when a run is resumed; the others define the problem and may not. Messages name them
    as the user gave them (`spelling.spelled`: `--init` for `initial` on the command line)."""

    spec: Path | None = None
    backend: str | None = None
    command: Command | None = None
    placements: tuple[dict[str, Pose], ...] | None = None
    seed: int | None = None
    initial: int | None = None
    trials: int | None = None
    method: str | None = None
    workers: int | None = None

    def given(self) -> dict[str, Any]:
        """The settings given (not None), by name."""
        return {item.name: getattr(self, item.name) for item in fields(self) if getattr(self, item.name) is not None}

    def fitted_to(self, task: Task) -> tuple["Overrides", str]:
        """These settings for a new run of `task`, and a note ('' for none): a budget of trials
        (`trials`) below the task's initial trials, with `initial` not given, lowers `initial`
        to it (a quick try of a task file) instead of refusing."""
        if self.trials is None or self.initial is not None or self.trials >= task.optimizer.initial or self.trials < 1:
            return self, ""
        note = f"note: {spelled('trials')} {self.trials} is below the task's {task.optimizer.initial} initial trials, so {spelled('initial')} is {self.trials} for this run"
        return replace(self, initial=self.trials), note

    def applied_to(self, task: Task) -> Task:
        """`task` with these settings in place of its own (validated as a task file's are)."""
        given = self.given()
        try:
            optimizer = replace(task.optimizer, **{key: value for key, value in given.items() if key in OPTIMIZER_KEYS})
        except ConfigError as error:
            raise self._attributed(str(error), task.source) from None
        return replace(task, optimizer=optimizer, **{key: value for key, value in given.items() if key not in OPTIMIZER_KEYS})

    def _attributed(self, message: str, source: Path) -> ConfigError:
        """An optimizer setting's error, naming the options given where the message is about them
        (`--workers 0 must be ...`), and the task file only where it is about the file's keys."""
        for key, value in self.given().items():
            message = message.replace(f"'optimizer.{key}' ({value})", f"{spelled(key)} {value}").replace(f"'optimizer.{key}'", f"{spelled(key)} {value}")
        return ConfigError(message if "'optimizer." not in message else f"{source}: {message}")

    @staticmethod
    def setting(task: Task, name: str) -> Any:
        """The value of setting `name` in `task`."""
        return getattr(task.optimizer, name) if name in OPTIMIZER_KEYS else getattr(task, name)


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
    loaded = read_behaviour(behaviour) if behaviour is not None else None
    semantics = choice(data.get("semantics", DEFAULT_SEMANTICS), SEMANTICS, path, "semantics")
    backend = choice(data.get("backend", DEFAULT_BACKEND), backend_names(), path, "backend")
    task = Task(
        name=_name(data.get("name", path.stem), path),
        spec=_existing(base, data["spec"], path, "spec"),
        model=_existing(base, data["model"], path, "model") if "model" in data else None,
        demos=_existing(base, data["demos"], path, "demos") if "demos" in data else None,
        behaviour=behaviour,
        states=integer(data.get("states", 6), path, "states", minimum=1, maximum=MAX_STATES),
        scene=scene_reference(str(data["scene"]), path, "task") if "scene" in data else loaded.scene if loaded is not None else "free_space",
        backend=backend,
        semantics=semantics,
        nu=number(data.get("nu", 1.0), path, "nu", positive=True),
        duration=number(data["duration"], path, "duration", positive=True),
        rate=number(data.get("rate", 100.0), path, "rate", positive=True),
        parameters=_skill_parameters(data.get("parameters", {}), path, loaded),
        optimizer=optimizer_from_yaml(data.get("optimizer", {}), path),
        source=path,
        command=_command(data["command"], path) if "command" in data else None,
        loaded_behaviour=loaded,
    )
    if "place" in data or "placements" in data:
        task = replace(task, placements=_placements(data, path, task.scene))
    problem = samples_problem(task.duration, task.rate)
    if problem:
        raise ConfigError(f"{path}: 'duration' and 'rate': {problem}")
    return task


def read_behaviour(path: Path) -> Any:
    """The behaviour file, read from its resolved path (so that the paths inside it are the same
    whether a task file names it relatively or a run's record absolutely)."""
    from stl_lfd.skill.behaviour import load_behaviour

    return load_behaviour(path.resolve())


def _placements(data: dict[str, Any], path: Path, scene_name: str) -> tuple[dict[str, Pose], ...]:
    """`place: {FRAME: POSE}` (one placement) or `placements: [{FRAME: POSE}, ...]`."""
    from stl_lfd.sim.scene_file import load_scene, placement_from_yaml

    if "place" in data and "placements" in data:
        raise ConfigError(f"{path}: give 'place' (one placement) or 'placements' (several), not both")
    scene = load_scene(scene_name)
    if "place" in data:
        return (placement_from_yaml(scene, data["place"], path, "place"),)
    items = data["placements"]
    if not isinstance(items, list) or not items or len(items) > MAX_PLACEMENTS:
        raise ConfigError(f"{path}: 'placements' must be a list of 1 to {MAX_PLACEMENTS} placements (each mapping frames to poses)")
    return tuple(placement_from_yaml(scene, item, path, f"placements[{index}]") for index, item in enumerate(items))


def _skill_parameters(data: Any, path: Path, behaviour: Any) -> dict[str, Parameters]:
    """`parameters` of a single-skill task, or per skill of a `behaviour`."""
    if behaviour is None:
        return {SINGLE_SKILL: parameters_from_yaml(data, path, "parameters")}
    skills = [step.name for step in behaviour.skills]
    check_keys(data, skills, path, "parameters")
    blocks = {name: parameters_from_yaml(block, path, f"parameters.{name}") for name, block in data.items()}
    if not blocks:
        raise ConfigError(f"{path}: 'parameters' selects nothing to optimise (name skills of the behaviour: {', '.join(skills)})")
    return blocks


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
    with located(path):
        return Command.parse(run, timeout, shell, cwd.resolve())


def _name(value: Any, path: Path) -> str:
    """The task's name: it names the default run directory, `runs/<name>`, so one plain word."""
    if not isinstance(value, (str, int)) or not str(value).strip() or "/" in str(value) or str(value) in (".", ".."):
        raise ConfigError(f"{path}: 'name' must be a plain name without '/' (got {shown(value)})")
    return str(value)


def _existing(base: Path, value: Any, path: Path, key: str) -> Path:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{path}: '{key}' must be a path (got {shown(value)})")
    resolved = Path(value) if Path(value).is_absolute() else base / value
    if not resolved.exists():
        raise ConfigError(f"{path}: '{key}' names {value}, which does not exist (paths are relative to the task file)")
    return resolved
