"""Running a sweep (see `sweep_file`): each cell an ordinary optimisation run in a scratch
folder, executed by a local process pool or by Ray tasks, its run directory moved into the
sweep folder when complete; `sweep.csv` holds one row per finished cell, and `aggregate`
summarises them over seeds.
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
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from stl_lfd.errors import RunError
from stl_lfd.files import check_output_folder, write_atomically
from stl_lfd.optim.runs.sweep_file import Cell, Sweep, load_sweep

RUNS_DIR = "runs"
TABLE_FILE = "sweep.csv"
SWEEP_FILE = "sweep.yaml"
SCRATCH_DIR = ".scratch"
COLUMNS = (
    "cell", "task", "variant", "method", "seed", "satisfied", "first_satisfied_trial", "best_robustness",
    "initial_robustness", "trials", "failed_trials", "wall_seconds",
)  # fmt: skip


@dataclass(frozen=True)
class CellResult:
    """What a cell's worker returns: its name, its row of `sweep.csv`, and its run directory
    as a tar archive."""

    name: str
    record: dict[str, Any]
    archive: bytes = field(repr=False)


def open_sweep(sweep_file: Path, out: Path | None = None, ray: str | None = None, watch_head: bool = False) -> tuple[Sweep, Path]:
    """The sweep of `sweep_file` and its folder (`out`, default `runs/<sweep name>`), checked
    to be writable. With `ray`, that Ray cluster is joined before any cell runs
    (`ray_workers.connect`; `watch_head`: the process ends when the cluster's head is lost)."""
    sweep = load_sweep(sweep_file)
    folder = check_output_folder(out or Path("runs") / sweep.name, "sweep folder")
    if ray is not None:
        from stl_lfd.optim.runs.ray_workers import connect

        connect(ray, watch=watch_head)
    return sweep, folder


def cell_results(jobs: int = 1, ray: str | None = None) -> Callable[[list[Cell]], Iterator[CellResult]]:
    """How `run_sweep` runs its cells: as Ray tasks on the cluster `ray` (`ray_results`), or
    by `jobs` local worker processes (`local_results`)."""
    if ray is not None:
        return lambda cells: ray_results(cells, ray)
    return lambda cells: local_results(cells, jobs)


def run_cell(cell: Cell) -> CellResult:
    """Run one cell in a scratch folder and return its record and its run directory (archived).
    Runs in a worker process (local pool or Ray task)."""
    from stl_lfd.optim.runs.prepare import start_run
    from stl_lfd.optim.runs.recorder import finish_run

    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory(prefix="stlopt-cell-") as scratch:
        run_dir = Path(scratch) / cell.name
        with start_run(cell.task, run_dir, inputs=cell.inputs) as prepared:
            finish_run(prepared)
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
    from stl_lfd.optim.runs.workers import run_stoppable, stop_children

    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"), initializer=_start_worker)
    futures = {pool.submit(run_stoppable, function, item): item for item in items}
    try:
        for future in as_completed(futures):
            yield futures[future], future.result()
    except BaseException as error:  # Ctrl-C, a failed item or a dead worker: stop the workers now
        stop_children()
        pool.shutdown(wait=True, cancel_futures=True)
        if isinstance(error, BrokenProcessPool):
            raise RunError(
                "a worker process died (killed, or crashed); the cells in flight are lost: run the same command again to do the missing ones"
            ) from None
        raise
    pool.shutdown()


def ray_map(function: Callable[[Any], Any], items: Iterable[Any], address: str | None) -> Iterator[tuple[Any, Any]]:
    """`(item, function(item))` for each item, computed by Ray tasks of one CPU each, in the
    order they finish. `address`: `auto` (the cluster this machine belongs to), a cluster's
    address, or None for a Ray already initialised by the caller (or a new local one)."""
    from stl_lfd.optim.runs.ray_workers import connect

    connect(address)
    import ray

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
    from stl_lfd.optim.runs.workers import THREAD_VARIABLES, stop_on_sigterm, watch_parent

    os.environ.update({name: "1" for name in THREAD_VARIABLES})
    stop_on_sigterm()
    watch_parent()


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
    from stl_lfd.optim.runs.directory import RunDirectory

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
