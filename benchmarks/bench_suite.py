"""The optimiser suite: problems nobody shaped for the optimiser, solved by every method over
many seeds.

    python -m benchmarks.bench_suite [--problems P ...] [--methods M ...] [--seeds 10]
                                     [--jobs 2] [--table] [--search N [--hold I=U ...]]

Each problem is a task file in `benchmarks/problems/` (its budget is the file's `trials`).
Methods: the tool's `stl`, `pi`, `logei` and `random`, run exactly as `stlopt optimize` runs
them (the unoptimised skill executed first, then the trials), and Optuna's default TPE
sampler driving the same objective (`pip install optuna`; it is a benchmark extra, not a
dependency of the tool). Every finished run is one line of `benchmarks/results/suite.jsonl`;
runs already there are not repeated, so the suite can be stopped and extended. `--table` only
prints the table of what is recorded. `--search N` runs N uniform random points per problem
(the large-budget check that a satisfying point exists) into `results/search.jsonl`;
`--hold INDEX=VALUE` (repeatable) holds unit coordinates fixed, a search directed to where
the problem's structure says the solutions are.

`PROBLEM+lag` runs a kinematic problem with a robot's tracking error (`LaggingBackend`), so
that the execution is not the plan that method `plan` scores; `PROBLEM+VARIANT` with a robot of
`benchmarks.robots.VARIANTS` (slowlag, sag, speed, accel, slow, fast, offset, noise, robot).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing
import os
import statistics
import time
import warnings
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from stl_lfd.optim import local_map
from stl_lfd.sim import Capabilities, KinematicBackend

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS_DIR = ROOT / "benchmarks" / "problems"
USER_TASKS_DIR = ROOT / "benchmarks" / "user_tasks"  # contact tasks written as a user writes them
RESULTS = ROOT / "benchmarks" / "results" / "suite.jsonl"
SEARCH_RESULTS = ROOT / "benchmarks" / "results" / "search.jsonl"
METHODS = ("stl", "plan", "pi", "logei", "random", "tpe", "plan-untracked", "plan-unbalanced", "stl-unbalanced")
# plan-untracked: method plan scoring the plan as it stands, as it did before the tracking model
# (for the problems whose robot does not execute the plan); METHOD-unbalanced: the spec's parts
# composed as recorded, as before `balance` (not run unless asked for)
DEFAULT_METHODS = METHODS[:-3]
TPE_STARTUP = 10  # Optuna's default n_startup_trials: random points before TPE proposes


def method_and_initial(text: str) -> tuple[str, int | None]:
    """A method of `METHODS`, or a variant `METHOD/mK` that runs it with K initial trials
    instead of the problem's (None: the problem's). `METHOD@LABEL` names records of the method
    from earlier code, kept under that label (`stl@step6`), for tables only."""
    method, _, label = text.partition("@")
    name, _, design = method.partition("/m")
    if name not in METHODS or (design and (name == "tpe" or not design.isdigit())) or (label and not label.isidentifier()):
        raise argparse.ArgumentTypeError(f"{text!r}: expected one of {', '.join(METHODS)}, METHOD/mK, or METHOD@LABEL with --table")
    return name, int(design) if design else None


def method_name(text: str) -> str:
    """`text` if it names a method or a variant (`method_and_initial`), for argparse."""
    method_and_initial(text)
    return text


def problem_names() -> list[str]:
    return sorted(path.stem for path in PROBLEMS_DIR.glob("*.yaml"))


def task_file(problem: str) -> Path:
    """A suite problem, a user-written task (`user_tasks/NAME/task.yaml`), or a bundled task
    (`configs/NAME.yaml`) by its name (a `+VARIANT`: the problem's file)."""
    name = problem.partition("+")[0]
    for path in (PROBLEMS_DIR / f"{name}.yaml", USER_TASKS_DIR / name / "task.yaml"):
        if path.exists():
            return path
    return ROOT / "configs" / f"{name}.yaml"


def user_check(problem: str):
    """The physical check of a user-written task (`check.py: done(signals, scene_path)`, which
    reads object poses, not the spec), or None."""
    import importlib.util

    path = USER_TASKS_DIR / problem.partition("+")[0] / "check.py"
    if not path.exists():
        return None
    spec = importlib.util.spec_from_file_location(f"user_check_{path.parent.name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.done


LAG_SECONDS = 0.3  # time constant of the tracking lag
SAG = np.array([0.0, 0.0, -0.01])  # m: the hand sits this far from where it is sent


class LaggingBackend(KinematicBackend):
    """The kinematic backend with the tracking error of a compliant robot: the hand follows the
    reference through a first-order lag of LAG_SECONDS and sits SAG below it. The reference
    (the plan) is unchanged, so its robustness is no longer the execution's."""

    capabilities = Capabilities()

    def run(self, reference, scene, rate, observer=None):
        from scipy.signal import lfilter

        from stl_lfd import SignalTable
        from stl_lfd.sim import Rollout

        rollout = super().run(reference, scene, rate, observer)
        times, columns = rollout.signals.times, dict(rollout.signals.columns)
        keep = float(np.exp(-(times[1] - times[0]) / LAG_SECONDS))
        sent = np.column_stack([columns[name] for name in ("x", "y", "z")])
        for axis, name in enumerate(("x", "y", "z")):
            start = columns[name][0]
            columns[name] = lfilter([1 - keep], [1, -keep], columns[name] - start) + start + SAG[axis]
        reached = np.column_stack([columns[name] for name in ("x", "y", "z")])
        return Rollout(SignalTable(times, columns, source="lagging kinematic rollout"), np.linalg.norm(reached - sent, axis=1))


def executed_as(problem: str, task):
    """`task` executing on the backend of `problem` in place of the kinematic one (`+lag`:
    `LaggingBackend`; `+VARIANT`: that robot of `benchmarks.robots.VARIANTS`), registered under
    the name `kinematic+VARIANT` (`stl_lfd.sim.register`, in this process)."""
    from benchmarks.robots import VARIANTS
    from stl_lfd.sim import register

    variant = problem.partition("+")[2]
    if variant == "mujoco":
        return task.with_overrides(backend="mujoco")
    if not variant or task.backend != "kinematic":
        return task
    robot = LaggingBackend() if variant == "lag" else VARIANTS[variant]
    name = f"kinematic+{variant}"
    register(name, type(f"{type(robot).__name__}Backend", (type(robot),), {"open": classmethod(lambda cls, options: robot)}), variant)
    return task.with_overrides(backend=name)


@contextlib.contextmanager
def untracked():
    """Within it, method plan scores the plan as it stands, whatever executes it."""
    from stl_lfd.optim import SkillObjective

    original = SkillObjective.plays_the_plan
    SkillObjective.plays_the_plan = property(lambda self: True)
    try:
        yield
    finally:
        SkillObjective.plays_the_plan = original


def unbalanced(task):
    """`task` with its method composing the spec's parts as recorded (tuning `balance: false`)."""
    from dataclasses import replace

    optimizer = task.optimizer
    settings = replace(optimizer.tuning_for(optimizer.method), balance=False)
    return replace(task, optimizer=replace(optimizer, tuning={**optimizer.tuning, optimizer.method: settings}))


def run_one(problem: str, method: str, seed: int) -> dict:
    """One optimisation run; returns its record (per-trial robustness and timings)."""
    warnings.simplefilter("ignore")
    _one_thread()
    from stl_lfd.optim import load_task

    task = _with_learned_model(load_task(task_file(problem)), problem.partition("+")[0])
    executed = executed_as(problem, task)
    if method == "tpe":
        trials, inserted, initial = _run_tpe(executed, seed)
    else:
        name, initial_trials = method_and_initial(method)
        base = name.removesuffix("-untracked").removesuffix("-unbalanced")
        tool_task = executed.with_overrides(method=base, seed=seed, initial=initial_trials)
        with untracked() if name == "plan-untracked" else contextlib.nullcontext():
            trials, inserted, initial = _run_tool(unbalanced(tool_task) if name.endswith("-unbalanced") else tool_task, user_check(problem))
    scored = [trial for trial in trials if trial.robustness is not None]
    best_x = max(scored, key=lambda trial: trial.robustness).x.tolist() if scored else None
    robustness = [trial.robustness for trial in trials]
    satisfied = [trial.trial for trial in scored if trial.robustness > 0]
    proposed = [trial.optimizer_seconds for trial in trials if trial.phase not in ("sobol", "startup")]
    return {
        "problem": problem,
        "method": method,
        "seed": seed,
        "budget": task.optimizer.trials,
        "backend": executed.backend,
        "initial_robustness": initial,
        "first_satisfied": satisfied[0] if satisfied else None,
        "best_robustness": max((value for value in robustness if value is not None), default=None),
        "optimizer_seconds": statistics.median(proposed) if proposed else 0.0,
        "rollout_seconds": statistics.median(trial.rollout_seconds for trial in trials),
        "robustness": robustness,
        "best_x": best_x,
        "processor": processor(),
    } | ({"inserted": inserted} if any(value is not None for value in inserted) else {})


def processor() -> str:
    """The processor's model name, and whether it has AVX-512: runs depend on the kind of
    processor (numpy and torch pick their kernels by the vector instructions there are)."""
    try:
        info = Path("/proc/cpuinfo").read_text()
    except OSError:
        return "unknown"
    name = next((line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("model name")), "unknown")
    return f"{name}, AVX-512" if " avx512f" in info else name


def _one_thread() -> None:
    """Each worker on one core: with `--jobs` workers on as many cores, extra BLAS or torch
    threads only fight each other (measured: proposals 5x slower)."""
    import torch

    torch.set_num_threads(1)


def _with_learned_model(task, problem: str):
    """The task with its demonstrations learned once (into `results/models/`) and loaded by
    every run after that: learning is deterministic, so only time is saved. The file is named
    by a digest of the demonstrations, the number of states and the skill model's code, so a
    change to any of them learns again instead of loading a model the tool would not learn."""
    from dataclasses import replace

    from stl_lfd.hsmm import learn_from_folder, save_model

    if task.demos is None:
        return task
    path = RESULTS.parent / "models" / f"{problem}-{_learning_digest(task.demos, task.states)}.npz"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_suffix(f".{multiprocessing.current_process().pid}.npz")
        save_model(learn_from_folder(task.demos, task.states)[0], partial)
        partial.replace(path)
    return replace(task, model=path, demos=None)


def _learning_digest(demos: Path, states: int) -> str:
    """A digest of what learning reads: the demonstration files, `states`, and the source of
    `stl_lfd.hsmm` and of the CSV reader."""
    import hashlib

    import stl_lfd.hsmm

    digest = hashlib.sha256(str(states).encode())
    package = Path(stl_lfd.hsmm.__file__).parent
    sources = sorted(package.glob("*.py")) + [package.parent / "signals.py"]
    for path in sorted(Path(demos).iterdir()) + sources:
        if path.is_file():
            digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:12]


def _run_tool(task, check=None) -> tuple[list, list[bool | None], float]:
    """The run's trials, whether each achieved the task physically (`check(signals, scene
    path)`, else for a contact task whether the shaft went into the hole; None where there is
    no check), and the unoptimised skill's robustness."""
    import tempfile

    from benchmarks.physical import holder_pose, is_contact_task, physically_inserted, scene_geometry
    from stl_lfd.optim import RunDirectory, finish_run, start_run

    with tempfile.TemporaryDirectory() as folder:
        prepared = start_run(task, Path(folder) / "run")
        finish_run(prepared)
        run = RunDirectory(Path(folder) / "run")
        trials, inserted = run.trials(), []
        for trial in trials:
            signals = run.recorded_signals(trial.trial) if check is not None or is_contact_task(task) else None
            if signals is None:
                inserted.append(None)
            elif check is not None:
                inserted.append(bool(check({"t": signals.times, **signals.columns}, task.scene)))
            else:
                inserted.append(physically_inserted(signals, holder_pose(task), scene_geometry(task.scene)))
        return trials, inserted, prepared.summary.initial_robustness


def _run_tpe(task, seed: int) -> tuple[list, list[None], float]:
    """The trials of Optuna's TPE on the task's objective (no physical check: None for each),
    and the unoptimised skill's robustness."""
    import optuna

    from stl_lfd.optim import Trial, objective_for, resolve, task_models

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    models = task_models(resolve(task))
    space, objective = objective_for(resolve(task), models)
    initial = objective.evaluate(models).robustness
    study = optuna.create_study(direction="maximize", sampler=optuna.samplers.TPESampler(seed=seed))
    distributions = {name: optuna.distributions.FloatDistribution(low, high) for name, low, high in zip(space.names, space.lower, space.upper)}
    trials = []
    for number in range(1, task.optimizer.trials + 1):
        start = time.perf_counter()
        trial = study.ask(distributions)
        x = np.array([trial.params[name] for name in space.names])
        chosen = time.perf_counter()
        try:
            robustness = float(objective(x).robustness)
            study.tell(trial, robustness)
        except Exception:
            robustness = None
            study.tell(trial, state=optuna.trial.TrialState.FAIL)
        phase, status = "startup" if number <= TPE_STARTUP else "tpe", "failed" if robustness is None else "ok"
        trials.append(Trial(number, phase, x, robustness, status, optimizer_seconds=chosen - start, rollout_seconds=time.perf_counter() - chosen))
    return trials, [None] * len(trials), initial


class HeldIndexError(ValueError):
    """A `--hold` index beyond the problem's dimension (known only once its space is built)."""


def random_search(problem: str, points: int, seed: int = 12345, held: dict[int, float] | None = None) -> dict:
    """The best of `points` uniform random points: evidence that the problem can be solved.

    `held` fixes unit coordinates (index -> value in [0, 1]) in every point: a search directed
    to where the problem's structure says the solutions are (recorded as `directed`)."""
    warnings.simplefilter("ignore")
    from stl_lfd.optim import load_task, objective_for, resolve, task_models

    task = executed_as(problem, load_task(task_file(problem)))
    inputs = resolve(task)
    space, objective = objective_for(inputs, task_models(inputs))
    held = held or {}
    if any(not 0 <= index < space.dimension for index in held):
        raise HeldIndexError(f"{problem}: --hold indices must be in 0..{space.dimension - 1}")
    unit = np.random.default_rng(seed).random((points, space.dimension))
    for index, value in held.items():
        unit[:, index] = value
    values = []
    for row in unit:
        try:
            values.append(float(objective(space.lower + row * (space.upper - space.lower)).robustness))
        except Exception:
            continue
    best = int(np.argmax(values))
    record = {
        "problem": problem,
        "points": points,
        "best_robustness": values[best],
        "best_unit_point": [round(float(v), 4) for v in unit[best]],
        "satisfied_fraction": float(np.mean(np.array(values) > 0)),
    }
    if held:
        record["directed"] = "unit coordinates held: " + ", ".join(f"{index} at {value}" for index, value in sorted(held.items()))
    return record


def held_coordinate(text: str) -> tuple[int, float]:
    """`--hold INDEX=VALUE`: a unit coordinate the search holds fixed."""
    index, _, value = text.partition("=")
    try:
        held = int(index), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected INDEX=VALUE, e.g. 17=1.0") from None
    if not 0 <= held[1] <= 1:
        raise argparse.ArgumentTypeError(f"{text!r}: a unit coordinate is within 0 and 1")
    return held


def _search_note(search: dict | None) -> str:
    """The table's `search best` cell: the best robustness and how many points satisfied the
    spec, of a uniform search or (`directed`: with coordinates held, or described by hand) of a
    search where the problem's structure says the solutions are."""
    if search is None:
        return ""
    if search.get("directed"):
        return f"{search['best_robustness']:+.4f} (directed: {round(search['satisfied_fraction'] * search['points'])} of {search['points']})"
    return f"{search['best_robustness']:+.4f} ({search['satisfied_fraction']:.1%} of {search['points']})"


def _recorded(path: Path) -> list[dict]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _append(path: Path, record: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as stream:
        stream.write(json.dumps(record) + "\n")


def _run_safely(job: tuple[str, str, int]) -> dict:
    try:
        return run_one(*job)
    except Exception as error:
        return {"error": f"{type(error).__name__}: {error}"}


def _search(job: tuple[str, int, dict[int, float]]) -> dict:
    problem, points, held = job
    return random_search(problem, points, held=held)


def run_suite(problems: list[str], methods: list[str], seeds: list[int], jobs: int, results: Path = RESULTS) -> None:
    done = {(r["problem"], r["method"], r["seed"]) for r in _recorded(results)}
    # seed by seed, so that a suite stopped early has whole seeds for every problem and method
    todo = [(p, m, s) for s in seeds for p in problems for m in methods if (p, m, s) not in done]
    console = Console(stderr=True)
    console.print(f"{len(todo)} runs to do ({len(done)} recorded)")
    for count, (job, record) in enumerate(local_map(_run_safely, todo, jobs), start=1):
        if "error" in record:  # one broken run must not lose the others
            console.print(f"[red]{job} failed: {record['error']}")
            continue
        _append(results, record)
        console.print(f"{count}/{len(todo)} {job}: first satisfied {record['first_satisfied']}, best {record['best_robustness']:.4f}")


def summarise(problems: list[str], methods: list[str], seeds: list[int] | None = None, results: Path = RESULTS) -> list[dict]:
    """One row per (problem, method) of the recorded runs, then one `all` row per method over
    the problems with a solution shown (a satisfying point in their search). Only the (problem,
    seed) pairs that every method has finished count, so methods are compared on the same seeds."""
    records = [r for r in _recorded(results) if r["problem"] in problems and r["method"] in methods and (seeds is None or r["seed"] in seeds)]
    finished: dict[tuple[str, int], set[str]] = {}
    for r in records:
        finished.setdefault((r["problem"], r["seed"]), set()).add(r["method"])
    records = [r for r in records if finished[(r["problem"], r["seed"])] >= set(methods)]
    searches = {r["problem"]: r for r in _recorded(SEARCH_RESULTS)}
    rows, totals = [], {method: [0, 0] for method in methods}
    for problem in problems:
        search = searches.get(problem)
        for method in methods:
            runs = [r for r in records if r["problem"] == problem and r["method"] == method]
            if not runs:
                continue
            firsts = [r["first_satisfied"] for r in runs if r["first_satisfied"] is not None]
            if search and search["best_robustness"] > 0:
                totals[method][0] += len(firsts)
                totals[method][1] += len(runs)
            rows.append(
                {
                    "problem": problem,
                    "budget": str(runs[0]["budget"]),
                    "search best": _search_note(search),
                    "method": method,
                    "seeds": " ".join(str(r["seed"]) for r in sorted(runs, key=lambda r: r["seed"])),
                    "satisfied": f"{len(firsts)}/{len(runs)}",
                    "median first": f"{statistics.median(firsts):g}" if firsts else "-",
                    "median best": f"{statistics.median(r['best_robustness'] for r in runs):+.4f}",
                    "optimiser s/trial": f"{statistics.median(r['optimizer_seconds'] for r in runs):.2f}",
                    "rollout s/trial": f"{statistics.median(r['rollout_seconds'] for r in runs):.2f}",
                }
                | _physical_columns(runs)
            )
    for method, (satisfied, total) in totals.items():
        if total:
            rows.append({"problem": "all", "method": method, "satisfied": f"{satisfied}/{total} ({100 * satisfied / total:.0f} %)"})
    return rows


def _physical_columns(runs: list[dict]) -> dict[str, str]:
    """For runs of a contact task checked physically (`inserted` per trial): how many runs' best
    trial is satisfied and physically inserted, and over all their trials how often the spec's
    verdict agrees with the check."""
    checked = [r for r in runs if "inserted" in r]
    if not checked:
        return {}
    best_inserted, agree, total = 0, 0, 0
    for r in checked:
        values = [(value, inside) for value, inside in zip(r["robustness"], r["inserted"]) if value is not None and inside is not None]
        if values:
            best_value, best_inside = max(values, key=lambda pair: pair[0])
            best_inserted += best_value > 0 and best_inside
        agree += sum((value > 0) == inside for value, inside in values)
        total += len(values)
    return {"satisfied & inserted": f"{best_inserted}/{len(checked)}", "verdict agrees": f"{agree}/{total} trials"}


def paired_firsts(problems: list[str], methods: list[str], seeds: list[int] | None = None, reference: str = "stl", results: Path = RESULTS) -> list[dict]:
    """Median trials to first satisfaction of `reference` and of each other method, over the
    (problem, seed) pairs that both satisfy."""
    records = {(r["problem"], r["method"], r["seed"]): r for r in _recorded(results) if seeds is None or r["seed"] in seeds}
    rows = []
    for method in methods:
        if method == reference:
            continue
        pairs = [
            (ours["first_satisfied"], theirs["first_satisfied"])
            for (problem, name, seed), ours in records.items()
            if name == reference and problem in problems and (theirs := records.get((problem, method, seed))) is not None
            if ours["first_satisfied"] is not None and theirs["first_satisfied"] is not None
        ]
        if pairs:
            ours, theirs = zip(*pairs)
            rows.append({"reference": reference, "against": method, "pairs": len(pairs), reference: statistics.median(ours), method: statistics.median(theirs)})
    return rows


COLUMNS = (
    "problem",
    "budget",
    "search best",
    "method",
    "seeds",
    "satisfied",
    "satisfied & inserted",
    "verdict agrees",
    "median first",
    "median best",
    "optimiser s/trial",
    "rollout s/trial",
)


def shown_columns(rows: list[dict]) -> tuple[str, ...]:
    """`COLUMNS` without the physical check's, when no row has them (no contact problem)."""
    optional = ("satisfied & inserted", "verdict agrees")
    return tuple(column for column in COLUMNS if column not in optional or any(column in row for row in rows))


def print_table(problems: list[str], methods: list[str], seeds: list[int] | None = None, markdown: bool = False, results: Path = RESULTS) -> None:
    rows = summarise(problems, methods, seeds, results)
    columns = shown_columns(rows)
    if markdown:
        print("| " + " | ".join(columns) + " |")
        print("|" + "---|" * len(columns))
        for row in rows:
            print("| " + " | ".join(row.get(column, "") for column in columns) + " |")
        print("\nMedian first satisfied trial on the pairs both satisfy:\n")
        for row in paired_firsts(problems, methods, seeds, results=results):
            ours, theirs = row["reference"], row["against"]
            print(f"- {ours} against {theirs}: {row['pairs']} pairs, {ours} {row[ours]:g}, {theirs} {row[theirs]:g}")
        return
    table = Table(title="Optimiser suite: success within the budget, over seeds")
    for column in columns:
        table.add_column(column)
    for row in rows:
        table.add_row(*(row.get(column, "") for column in columns))
    Console().print(table)


def main(argv: list[str] | None = None) -> None:
    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(variable, "1")  # inherited by the spawned workers
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", nargs="+", default=problem_names())
    parser.add_argument(
        "--methods",
        nargs="+",
        default=list(DEFAULT_METHODS),
        type=method_name,
        help="METHOD, METHOD/mK for K initial trials, or METHOD@LABEL (earlier code's records, with --table)",
    )
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--table", action="store_true", help="only print the table of recorded runs")
    parser.add_argument("--search", type=int, default=0, help="random points per problem for the existence check")
    parser.add_argument(
        "--hold",
        type=held_coordinate,
        action="append",
        default=[],
        metavar="INDEX=VALUE",
        help="with --search: hold this unit coordinate fixed in every point (repeatable)",
    )
    parser.add_argument("--markdown", action="store_true", help="print the table in Markdown")
    parser.add_argument(
        "--results",
        type=Path,
        default=RESULTS,
        help="the records to extend and print (default results/suite.jsonl; another machine's go in a file of their own)",
    )
    args = parser.parse_args(argv)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    if not args.table and any("@" in method for method in args.methods):
        parser.error("METHOD@LABEL names records of earlier code: use it with --table")
    if args.hold and not args.search:
        parser.error("--hold holds coordinates of a search: use it with --search N")
    if args.search:
        held = dict(args.hold)
        try:
            for _, record in local_map(_search, [(problem, args.search, held) for problem in args.problems], args.jobs):
                _append(SEARCH_RESULTS, record)
                Console(stderr=True).print(record)
        except HeldIndexError as error:
            parser.error(str(error))
    elif not args.table:
        run_suite(args.problems, args.methods, seeds, args.jobs, args.results)
    print_table(args.problems, args.methods, seeds, args.markdown, args.results)


if __name__ == "__main__":
    main()
