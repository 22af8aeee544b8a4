"""Sweep files: a grid of optimisation runs (task files x variants x methods x seeds), each cell an
ordinary run directory, executed by a local process pool or by Ray tasks.

A sweep file (YAML, e.g. `sweeps/phi1_methods.yaml`; paths relative to it):

```
name: phi1-methods          # the default folder: runs/<name>
tasks: [../configs/phi1.yaml]
methods: [stl, random]      # default: each task's own method
seeds: 4                    # seeds 0-3, or a list [0, 5, 7]
backend: kinematic          # optional, for every cell; also `trials` (N) and `initial` (M)
variants:                   # optional: named changes of task-file keys, merged into every task
  narrow: {parameters: {means: {beta: 1.0}}}
```

The sweep folder holds `sweep.yaml` (the file as used), `runs/<cell>/` (one run directory per
finished cell) and `sweep.csv` (one row per finished cell). A cell runs in a scratch folder and
its run directory is moved into `runs/` when it is complete, so a killed sweep loses only the
cells in flight and a re-run does only the missing cells. On Ray, a cell's run directory comes
back to the driver as an archive.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from stl_lfd.errors import ConfigError
from stl_lfd.limits import MAX_SEED
from stl_lfd.optim.inputs import resolve
from stl_lfd.optim.methods import method_names
from stl_lfd.optim.runs.resume import inputs_record
from stl_lfd.optim.task import Overrides, Task, parse_task
from stl_lfd.sim.registry import backend_names
from stl_lfd.yamlfile import check_keys, integer, read_yaml, shown

MAX_CELLS = 10_000


@dataclass(frozen=True)
class Cell:
    """One run of a sweep: a task (with the variant's changes and the sweep's overrides) and
    the record of its inputs for `inputs.json`."""

    name: str
    task_name: str
    variant: str
    method: str
    seed: int
    task: Task
    inputs: dict[str, Any] = field(repr=False, compare=False)


@dataclass(frozen=True)
class Sweep:
    name: str
    cells: tuple[Cell, ...]
    source: Path
    text: str


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep file, and every task of every cell (errors before any run)."""
    path = Path(path)
    data = read_yaml(path)
    check_keys(data, ("name", "tasks", "methods", "seeds", "backend", "trials", "initial", "variants"), path, required=("tasks",))
    name = str(data.get("name", path.stem))
    if not name.strip() or "/" in name:
        raise ConfigError(f"{path}: 'name' must be a plain name without '/' (got {shown(name)})")
    task_files = _task_files(data["tasks"], path)
    methods = _methods(data.get("methods"), path)
    seeds = _seeds(data.get("seeds", [0]), path)
    variants = _variants(data.get("variants"), path)
    overrides = {key: integer(data[key], path, key, minimum=1) for key in ("trials", "initial") if key in data}
    if "backend" in data:
        overrides["backend"] = data["backend"]
    if "backend" in overrides and overrides["backend"] not in backend_names():
        raise ConfigError(f"{path}: 'backend' must be one of {', '.join(backend_names())} (got {shown(overrides['backend'])})")
    count = len(task_files) * len(variants) * max(len(methods), 1) * len(seeds)
    if count > MAX_CELLS:
        raise ConfigError(f"{path}: {count} cells is above the limit of {MAX_CELLS}")
    cells = tuple(
        _cell(task_file, variant, changes, method, seed, overrides, path)
        for task_file in task_files
        for variant, changes in variants.items()
        for method in (methods or [None])
        for seed in seeds
    )
    names = [cell.name for cell in cells]
    if len(set(names)) != len(names):
        duplicate = next(name for name in names if names.count(name) > 1)
        raise ConfigError(f"{path}: two cells are both called {duplicate} (give the tasks different names)")
    return Sweep(name, cells, path, path.read_text())


def _task_files(value: Any, path: Path) -> list[Path]:
    if not isinstance(value, list) or not value or not all(isinstance(item, str) for item in value):
        raise ConfigError(f"{path}: 'tasks' must be a non-empty list of task files (got {shown(value)})")
    files = [path.parent / item for item in value]
    for item, file in zip(value, files):
        if not file.is_file():
            raise ConfigError(f"{path}: 'tasks' names {item}, which does not exist (paths are relative to the sweep file)")
    return files


def _methods(value: Any, path: Path) -> list[str]:
    if value is None:
        return []
    if not isinstance(value, list) or not value or any(method not in method_names() for method in value):
        raise ConfigError(f"{path}: 'methods' must be a list of {', '.join(method_names())} (got {shown(value)})")
    return list(dict.fromkeys(value))


def _seeds(value: Any, path: Path) -> list[int]:
    if isinstance(value, int) and not isinstance(value, bool):
        count = integer(value, path, "seeds", minimum=1, maximum=MAX_CELLS)
        return list(range(count))
    if not isinstance(value, list) or not value:
        raise ConfigError(f"{path}: 'seeds' must be a number of seeds or a list of seeds (got {shown(value)})")
    seeds = [integer(item, path, "seeds", minimum=0, maximum=MAX_SEED) for item in value]
    return list(dict.fromkeys(seeds))


def _variants(value: Any, path: Path) -> dict[str, dict[str, Any]]:
    if value is None:
        return {"": {}}
    if not isinstance(value, dict) or not value:
        raise ConfigError(f"{path}: 'variants' must map variant names to task-file changes")
    for name, changes in value.items():
        if not isinstance(name, str) or not name.strip() or "/" in name:
            raise ConfigError(f"{path}: variant names must be plain names (got {shown(name)})")
        if not isinstance(changes, dict):
            raise ConfigError(f"{path}: 'variants.{name}' must be a mapping of task-file keys")
    return dict(value)


def _cell(task_file: Path, variant: str, changes: dict, method: str | None, seed: int, overrides: dict, path: Path) -> Cell:
    data = merged(read_yaml(task_file), changes)
    where = Path(f"{task_file}" + (f" (variant {variant} of {path.name})" if variant else ""))
    try:
        file_task = parse_task(data, task_file)
    except ConfigError as error:
        raise ConfigError(f"{error} (in {where})") from None
    given = Overrides(seed=seed, method=method, backend=overrides.get("backend"), trials=overrides.get("trials"), initial=overrides.get("initial"))
    task = given.applied_to(file_task)
    task_name = file_task.name
    name = "-".join(part for part in (task_name, variant, task.optimizer.method, f"seed{seed}") if part)
    return Cell(name, task_name, variant, task.optimizer.method, seed, task, inputs_record(file_task, given, resolve(task)))


def merged(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """`base` with `changes` applied: mappings merge key by key, anything else is replaced."""
    result = dict(base)
    for key, value in changes.items():
        result[key] = merged(result[key], value) if isinstance(value, dict) and isinstance(result.get(key), dict) else value
    return result
