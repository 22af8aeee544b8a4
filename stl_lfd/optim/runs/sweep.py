"""Sweeps: a grid of optimisation runs (task files x variants x methods x seeds), each cell an
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

import csv
import io
import json
import os
import shutil
import statistics
import tarfile
import tempfile
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from stl_lfd.choices import BACKENDS, METHODS
from stl_lfd.errors import ConfigError, RunError
from stl_lfd.files import write_atomically
from stl_lfd.limits import MAX_SEED
from stl_lfd.optim.task import Task, parse_task
from stl_lfd.yamlfile import check_keys, integer, read_yaml, shown

RUNS_DIR = "runs"
TABLE_FILE = "sweep.csv"
SWEEP_FILE = "sweep.yaml"
SCRATCH_DIR = ".scratch"
COLUMNS = (
    "cell", "task", "variant", "method", "seed", "satisfied", "first_satisfied_trial", "best_robustness",
    "initial_robustness", "trials", "failed_trials", "wall_seconds",
)  # fmt: skip
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


@dataclass(frozen=True)
class CellResult:
    """What a cell's worker returns: its name, its row of `sweep.csv`, and its run directory
    as a tar archive."""

    name: str
    record: dict[str, Any]
    archive: bytes = field(repr=False)


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
    if "backend" in overrides and overrides["backend"] not in BACKENDS:
        raise ConfigError(f"{path}: 'backend' must be one of {', '.join(BACKENDS)} (got {shown(overrides['backend'])})")
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
    if not isinstance(value, list) or not value or any(method not in METHODS for method in value):
        raise ConfigError(f"{path}: 'methods' must be a list of {', '.join(METHODS)} (got {shown(value)})")
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
    from stl_lfd.optim.resume import inputs_record

    data = merged(read_yaml(task_file), changes)
    where = Path(f"{task_file}" + (f" (variant {variant} of {path.name})" if variant else ""))
    try:
        file_task = parse_task(data, task_file)
    except ConfigError as error:
        raise ConfigError(f"{error} (in {where})") from None
    given = {"seed": seed, "method": method, "backend": overrides.get("backend"), "trials": overrides.get("trials"), "initial": overrides.get("initial")}
    task = file_task.with_overrides(**given)
    task_name = file_task.name
    name = "-".join(part for part in (task_name, variant, task.optimizer.method, f"seed{seed}") if part)
    return Cell(name, task_name, variant, task.optimizer.method, seed, task, inputs_record(file_task, given, task))


def merged(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """`base` with `changes` applied: mappings merge key by key, anything else is replaced."""
    result = dict(base)
    for key, value in changes.items():
        result[key] = merged(result[key], value) if isinstance(value, dict) and isinstance(result.get(key), dict) else value
    return result


def run_cell(cell: Cell) -> CellResult:
    """Run one cell in a scratch folder and return its record and its run directory (archived).
    Runs in a worker process (local pool or Ray task)."""
    from stl_lfd.optim.run import optimise, start_run

    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory(prefix="stlopt-cell-") as scratch:
        run_dir = Path(scratch) / cell.name
        with start_run(cell.task, run_dir, inputs=cell.inputs) as prepared:
            optimise(prepared)
        (run_dir / ".lock").unlink(missing_ok=True)
        buffer = io.BytesIO()
        with tarfile.open(fileobj=buffer, mode="w:gz") as archive:
            archive.add(run_dir, arcname=cell.name)
        return CellResult(cell.name, cell_record(cell, run_dir), buffer.getvalue())


def cell_record(cell: Cell, run_dir: Path) -> dict[str, Any]:
    """The row of `sweep.csv` of a finished cell, from its run's summary (`wall_seconds`: the
    run's own time, the unoptimised execution and the trials)."""
    summary = json.loads((run_dir / "summary.json").read_text())
    return {
        "cell": cell.name, "task": cell.task_name, "variant": cell.variant, "method": cell.method, "seed": cell.seed,
        "satisfied": summary["satisfied"], "first_satisfied_trial": summary.get("first_satisfied_trial"),
        "best_robustness": summary.get("best_robustness"), "initial_robustness": summary["initial_robustness"],
        "trials": summary["trials"], "failed_trials": summary.get("failed_trials", 0),
        "wall_seconds": round(summary["wall_seconds"], 3),
    }  # fmt: skip


def local_map(function: Callable[[Any], Any], items: Iterable[Any], jobs: int) -> Iterator[tuple[Any, Any]]:
    """`(item, function(item))` for each item, computed by `jobs` spawned worker processes of
    one thread each (forking after torch or pybullet started threads can deadlock), in the
    order they finish. `function` must be importable by the workers (a module-level function)."""
    import multiprocessing

    items = list(items)
    if not items:
        return
    from stl_lfd.optim.workers import run_stoppable, stop_children

    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"), initializer=_start_worker)
    futures = {pool.submit(run_stoppable, function, item): item for item in items}
    try:
        for future in as_completed(futures):
            yield futures[future], future.result()
    except BaseException:  # Ctrl-C or a failed item: stop the workers now, not after their items
        stop_children()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown()


def ray_map(function: Callable[[Any], Any], items: Iterable[Any], address: str | None) -> Iterator[tuple[Any, Any]]:
    """`(item, function(item))` for each item, computed by Ray tasks of one CPU each, in the
    order they finish. `address`: `auto` (the cluster this machine belongs to), a cluster's
    address, or None for a Ray already initialised by the caller (or a new local one)."""
    try:
        import ray
    except ImportError:
        raise ConfigError("--ray needs Ray: pip install 'stlopt[ray]'") from None
    if not ray.is_initialized():
        ray.init(address=address, runtime_env={"env_vars": {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}}, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(function)
    pending = {remote.remote(item): item for item in items}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            item = pending.pop(done[0])
            yield item, ray.get(done[0])
    except BaseException:
        for reference in pending:
            ray.cancel(reference, force=True)
        raise


def local_results(cells: Iterable[Cell], jobs: int) -> Iterator[CellResult]:
    """The cells run by `jobs` local worker processes, in the order they finish."""
    return (result for _, result in local_map(run_cell, cells, jobs))


def ray_results(cells: Iterable[Cell], address: str | None) -> Iterator[CellResult]:
    """The cells run as Ray tasks (see `ray_map`), in the order they finish."""
    return (result for _, result in ray_map(run_cell, cells, address))


def _start_worker() -> None:
    """A local worker: one thread; stopped by SIGTERM, its cell's scratch folder is removed."""
    from stl_lfd.optim.workers import THREAD_VARIABLES, stop_on_sigterm

    os.environ.update({name: "1" for name in THREAD_VARIABLES})
    stop_on_sigterm()


def run_sweep(
    sweep: Sweep,
    out: Path,
    results: Callable[[list[Cell]], Iterator[CellResult]],
    on_cell: Callable[[CellResult | None, int, int], None] = lambda result, done, total: None,
) -> list[dict[str, Any]]:
    """Run the cells of `sweep` that `out` does not hold yet with `results` (`local_results` or
    `ray_results`, given the cells to run), moving each finished run into `out/runs/` and
    rewriting `sweep.csv`; returns every finished cell's record, in the sweep's order.
    `on_cell(result, done, total)` is called once with None before the first cell runs, then
    after each cell."""
    out = Path(out)
    runs = out / RUNS_DIR
    runs.mkdir(parents=True, exist_ok=True)
    write_atomically(out / SWEEP_FILE, sweep.text)
    shutil.rmtree(out / SCRATCH_DIR, ignore_errors=True)
    records = {cell.name: cell_record(cell, runs / cell.name) for cell in sweep.cells if _finished(cell, runs / cell.name)}
    missing = [cell for cell in sweep.cells if cell.name not in records]
    total = len(sweep.cells)
    on_cell(None, len(records), total)
    write_table(out, sweep, records)
    for result in results(missing):
        _unpack(result, out)
        records[result.name] = result.record
        write_table(out, sweep, records)
        on_cell(result, len(records), total)
    return [records[cell.name] for cell in sweep.cells if cell.name in records]


def _finished(cell: Cell, run_dir: Path) -> bool:
    """Whether `run_dir` holds the cell's complete run; another run there is an error."""
    if not run_dir.exists():
        return False
    from stl_lfd.optim.rundir import RunDirectory

    run = RunDirectory.open(run_dir)
    if _plain_json(run.inputs()) != _plain_json(cell.inputs):
        raise RunError(
            f"{run_dir}: holds another run than the sweep's cell {cell.name} (other task settings or inputs); remove it or sweep into another folder"
        )
    return run.summary().complete


def _plain_json(value: Any) -> Any:
    return json.loads(json.dumps(value, sort_keys=True))


def _unpack(result: CellResult, out: Path) -> None:
    """Extract a cell's archived run directory into `out/runs/<cell>` (in one rename)."""
    scratch = out / SCRATCH_DIR / result.name
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    with tarfile.open(fileobj=io.BytesIO(result.archive), mode="r:gz") as archive:
        archive.extractall(scratch, filter="data")
    target = out / RUNS_DIR / result.name
    shutil.rmtree(target, ignore_errors=True)
    os.replace(scratch / result.name, target)
    shutil.rmtree(scratch, ignore_errors=True)


def write_table(out: Path, sweep: Sweep, records: dict[str, dict[str, Any]]) -> None:
    """`sweep.csv`: one row per finished cell, in the sweep's order."""
    body = io.StringIO()
    writer = csv.DictWriter(body, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    for cell in sweep.cells:
        if cell.name in records:
            writer.writerow({key: ("" if value is None else value) for key, value in records[cell.name].items()})
    write_atomically(out / TABLE_FILE, body.getvalue())


@dataclass(frozen=True)
class Group:
    """The cells of one (task, variant, method), aggregated over seeds."""

    task: str
    variant: str
    method: str
    runs: int
    satisfied: int
    median_first_satisfied: float | None
    median_best_robustness: float | None
    median_wall_seconds: float

    @property
    def success_rate(self) -> float:
        return self.satisfied / self.runs


def aggregate(records: list[dict[str, Any]]) -> list[Group]:
    """One `Group` per (task, variant, method), in the order they first appear."""
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for record in records:
        groups.setdefault((record["task"], record["variant"], record["method"]), []).append(record)
    return [_group(key, members) for key, members in groups.items()]


def _group(key: tuple[str, str, str], members: list[dict[str, Any]]) -> Group:
    firsts = [record["first_satisfied_trial"] for record in members if record["first_satisfied_trial"] not in (None, "")]
    bests = [float(record["best_robustness"]) for record in members if record["best_robustness"] not in (None, "")]
    satisfied = sum(1 for record in members if str(record["satisfied"]) in ("True", "true", "1"))
    return Group(
        *key, runs=len(members), satisfied=satisfied,
        median_first_satisfied=statistics.median(float(value) for value in firsts) if firsts else None,
        median_best_robustness=statistics.median(bests) if bests else None,
        median_wall_seconds=statistics.median(float(record["wall_seconds"]) for record in members),
    )  # fmt: skip


def read_table(out: Path) -> list[dict[str, Any]]:
    """The rows of a sweep folder's `sweep.csv`."""
    path = Path(out) / TABLE_FILE
    if not path.is_file():
        raise RunError(f"{out}: not a sweep folder (no {TABLE_FILE})")
    with open(path, newline="") as stream:
        return list(csv.DictReader(stream))
