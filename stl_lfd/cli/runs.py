"""`stlopt optimize`, `ask`, `tell` and `sweep`: optimisation runs, in this process, trial by trial from elsewhere, or a grid of them."""

from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional

import typer

from stl_lfd.cli.options import (
    PLACE_HELP,
    BackendOption,
    CommandOption,
    CommandTimeoutOption,
    InitOption,
    IterationsOption,
    MethodOption,
    SeedOption,
    command_of,
    placements_of,
)
from stl_lfd.cli.program import PlainUsage, app, print_table, progress_bar, to_stderr, user_errors

if TYPE_CHECKING:
    from stl_lfd.optim.runs.asktell import Asked, Told
    from stl_lfd.optim.runs.sweep import CellResult
    from stl_lfd.optim.trials import Trial


@app.command(cls=PlainUsage)
def optimize(
    task_file: Optional[Path] = typer.Argument(
        None, metavar="[TASK_FILE]", help="Task file (YAML), e.g. configs/phi1.yaml (default: the one in configs/ that names --spec)."
    ),
    spec: Optional[Path] = typer.Option(None, "--spec", help="Use this STL spec instead of the task's; alone, the task file that names it."),
    demos: Optional[Path] = typer.Option(
        None, "--demos", help="Without a task file for --spec: a default task on the skill learned from these demonstrations."
    ),
    model: Optional[Path] = typer.Option(None, "--model", help="Without a task file for --spec: a default task on this model file."),
    iterations: Optional[int] = IterationsOption,
    init: Optional[int] = InitOption,
    seed: Optional[int] = SeedOption,
    out: Optional[Path] = typer.Option(None, "--out", help="Run directory (default: runs/<task name>)."),
    resume: bool = typer.Option(False, "--resume", help="Continue the run in --out (or runs/<task name>) where it stopped."),
    backend: Optional[BackendOption] = typer.Option(None, help="Execution backend (default: the task's)."),
    method: Optional[MethodOption] = typer.Option(
        None,
        help="stl (composite BO on the spec's parts), plan (the same, with each part's plan as its prior), pi (the paper), logei, or random search (default: the task's).",
    ),
    command: Optional[str] = CommandOption,
    command_timeout: Optional[float] = CommandTimeoutOption,
    workers: Optional[int] = typer.Option(None, "--workers", help="Trials run at once, each batch proposed together (default: the task's, or 1)."),
    ray: Optional[str] = typer.Option(
        None,
        "--ray",
        help="Run the trials on a Ray cluster, --workers at once: 'auto' (this machine's cluster) or a cluster address (default: local processes).",
    ),
    place: list[str] = typer.Option([], "--place", help=PLACE_HELP + " Replaces the task's placements."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="On stderr, only what runs and the verdict (no line per trial); errors still show."),
    dry_run: bool = typer.Option(
        False,
        "--dry-run",
        help="Run no trial: print each parameter's range (mm, deg, s) and what the plans at the box's centre and corners say of each part of the spec.",
    ),
) -> None:
    """Optimise a skill so that its execution satisfies the task's STL specification.

    M initial trials, then the task's method until N trials: plan (the default) scores the plan
    of every candidate (its reference, as the kinematic backend executes it) before spending a
    trial on it, and models how each part of the spec's execution differs from its plan; stl
    models each top-level part of the spec with its own GP after M scrambled-Sobol trials and
    maximises expected improvement of their composition in a trust region; pi is the paper's
    Algorithm 1 (probability of improvement on one GP of the robustness). Each trial is recorded in the run directory as it finishes; the final
    summary.json is printed on stdout.

    Without a task file, --spec SPEC runs the task file in configs/ (beside the spec's folder)
    that names SPEC; where none does, --demos DIR or --model FILE builds a default task (free
    space, PyBullet, the means of every state but the first, every duration and the transition
    band; method plan, 32 trials).

    Examples:

    \b
        stlopt optimize configs/phi1.yaml --seed 3 --out runs/phi1-seed3
        stlopt optimize configs/phi1.yaml --out runs/phi1-seed3 --resume -N 48
        stlopt optimize configs/phi1.yaml --workers 4 --ray auto
        stlopt optimize --spec specs/phi2.stl
        stlopt optimize --spec my.stl --demos demos/three_regions
    """
    from stl_lfd.optim import Overrides, open_run
    from stl_lfd.optim.default_task import task_to_run
    from stl_lfd.progress import finish_printed

    with user_errors():
        file_task = task_to_run(task_file, spec, demos, model, say=to_stderr)
        given = Overrides(
            spec=spec, seed=seed, initial=init, trials=iterations, backend=backend.value if backend else None, method=method.value if method else None,
            workers=workers, command=command_of(command, command_timeout, file_task.command), placements=placements_of(file_task.scene, place),
        )  # fmt: skip
        if dry_run:
            from stl_lfd.optim.box import task_box

            return _print_box(task_box(file_task, given))
        run_dir = out or Path("runs") / file_task.name
        prepared = open_run(file_task, given, run_dir, resume, (lambda message: None) if quiet else to_stderr, ray, watch_head=True)
    again = _optimize_again(task_file, spec, demos, model, run_dir)
    with prepared, user_errors(on_interrupt=f"interrupted; the finished trials are kept. Continue with: {again}"):
        summary = finish_printed(prepared, quiet, ray)
    print(json.dumps(summary.to_json(), indent=2))


def _print_box(report) -> None:
    """The tables of `stlopt optimize --dry-run` on stdout."""
    print_table(
        ["parameter", "unit", "unoptimised", "lower", "upper"],
        [[item.name, item.unit or "-", f"{item.initial:.4g}", f"{item.lower:.4g}", f"{item.upper:.4g}"] for item in report.parameters],
    )
    print()
    print_table(
        ["part of the spec", "unoptimised plan", "centre's plan", "best plan", f"plans satisfying (of {report.points})"],
        [[part.name, f"{part.unoptimised:+.4g}", f"{part.centre:+.4g}", f"{part.best:+.4g}", str(part.satisfied)] for part in report.parts],
    )
    print("\nplans are the kinematic backend's: they record no force (a part on the force reads as nothing touched)", file=sys.stderr)


def _optimize_again(task_file: Optional[Path], spec: Optional[Path], demos: Optional[Path], model: Optional[Path], run_dir: Path) -> str:
    """The command that continues an interrupted `stlopt optimize`."""
    skill = "".join(f" {option} {path}" for option, path in (("--demos", demos), ("--model", model)) if path is not None)
    return f"stlopt optimize {task_file or f'--spec {spec}{skill}'} --out {run_dir} --resume"


@app.command(cls=PlainUsage)
def ask(
    target: Path = typer.Argument(..., metavar="TASK_FILE_OR_RUN", help="A task file (starts a run) or a run directory."),
    out: Optional[Path] = typer.Option(None, "--out", help="With a task file: the run directory (default: runs/<task name>)."),
    spec: Optional[Path] = typer.Option(None, "--spec", help="Use this STL spec instead of the task's (a new run only)."),
    iterations: Optional[int] = IterationsOption,
    init: Optional[int] = InitOption,
    seed: Optional[int] = SeedOption,
    method: Optional[MethodOption] = typer.Option(None, help="Optimiser method (default: the task's)."),
    workers: Optional[int] = typer.Option(None, "--workers", help="Trials handed out at once, to as many robots (a new run only; default: the task's, or 1)."),
    robot: str = typer.Option("", "--robot", metavar="NAME", help="Who executes the trial: each robot of a fleet holds one trial at a time."),
) -> None:
    """Hand out the next trial to execute elsewhere: write its reference CSV, print its path.

    The first ask of a task file creates the run with trial 0, the unoptimised skill. Execute
    the reference (the executor's contract is on the documentation's page on execution and
    real robots), then record the signals with 'stlopt tell'. Asking again before telling
    prints the same trial. When the run has all its trials,
    nothing is printed on stdout. The same seed gives the same trials as 'stlopt optimize'.
    References outside the scene's safety limits are recorded as failed trials, never handed out.

    A fleet: with --workers N (or the task's optimizer.workers), N robots each ask with their
    --robot name and hold a trial at once; the trials are those of 'stlopt optimize --workers N'.

    Examples (then execute the printed reference and 'stlopt tell' its signals):

    \b
        stlopt ask configs/phi1.yaml --out runs/robot
        stlopt ask runs/robot
        stlopt ask runs/lab --robot left
    """
    from stl_lfd.optim import Overrides
    from stl_lfd.optim.runs.targets import ask_run

    given = Overrides(spec=spec, seed=seed, initial=init, trials=iterations, method=method.value if method else None, workers=workers)
    with user_errors():
        run_dir, asked = ask_run(target, out, given, on_refused=_print_refused, robot=robot, learn_progress=to_stderr)
    _print_asked(run_dir, asked, robot)


def _print_refused(trial: Trial) -> None:
    print(f"trial {trial.trial} refused: {trial.error}", file=sys.stderr)


def _print_asked(run_dir: Path, asked: Optional[Asked], robot: str) -> None:
    """The reference to execute on stdout, and on stderr what it is and what to do next (or
    that the run has all its trials)."""
    from stl_lfd.optim.runs.pending import still_out

    if asked is None:
        out = still_out(run_dir)
        done = (
            f"every trial is handed out; the run is complete once {out} {'is' if out.count(',') == 0 else 'are'} told" if out else "the run has all its trials"
        )
        print(f"{run_dir}: {done} (raise --iterations to extend it; stlopt report {run_dir})", file=sys.stderr)
        return
    print(asked.reference)
    what = "the unoptimised skill" if asked.trial == 0 else "an initial trial, chosen on its plan" if asked.phase == "design" else f"chosen by {asked.phase}"
    state = ("still pending" if asked.again else "to execute") + (f" on robot {robot}" if robot else "")
    which = f" --trial {asked.trial}" if robot else ""  # a fleet's robots tell their own trial
    print(f"trial {asked.trial} ({what}) {state}; then: stlopt tell {shlex.quote(str(run_dir))} SIGNALS.csv{which}", file=sys.stderr)


@app.command(cls=PlainUsage)
def tell(
    context: typer.Context,
    run_dir: Path = typer.Argument(..., metavar="RUN_DIR", help="The run directory that 'stlopt ask' handed the trial out of."),
    signals: Optional[Path] = typer.Argument(None, metavar="SIGNALS_CSV", help="The signals recorded while executing the pending trial."),
    failed: Optional[str] = typer.Option(None, "--failed", help="Record the pending trial as failed, with this reason, instead of signals."),
    abandon: bool = typer.Option(False, "--abandon", help="Record the pending trial as failed: it will never be told (a robot gone)."),
    trial: Optional[int] = typer.Option(
        None, "--trial", min=0, metavar="N", help="Which pending trial (default: the one whose folder holds the signals, or the only one)."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (trial, robustness, satisfied, best) instead of the number."),
) -> None:
    """Record the signals of a trial 'stlopt ask' handed out, and print its robustness.

    Trials handed out to a fleet may be told in any order: one told before those handed out
    ahead of it is recorded as soon as they are.

    Examples:

    \b
        stlopt tell runs/robot signals.csv
        stlopt tell runs/robot --failed "protective stop at t=4 s"
        stlopt tell runs/lab --trial 7 --abandon
    """
    from stl_lfd.optim.runs.asktell import ABANDONED
    from stl_lfd.optim.runs.asktell import tell as tell_trial

    if sum([signals is not None, failed is not None, abandon]) != 1:  # mistakes in the command line itself: usage, exit 2
        context.fail("give the signals CSV of the pending trial, --failed REASON or --abandon (one of them)")
    if failed is not None and not failed.strip():
        context.fail("--failed needs a reason, such as --failed 'protective stop at t = 4 s'")
    with user_errors():
        told = tell_trial(run_dir, signals, ABANDONED if abandon else failed, trial)
    _print_told(told, run_dir, as_json)


def _print_told(told: Told, run_dir: Path, as_json: bool) -> None:
    """The robustness (or with `as_json`, one JSON object) on stdout; on stderr the trial's
    outcome, whether it waits for trials handed out before it, the best so far and what is left."""
    from stl_lfd.optim.runs.pending import handed_out

    summary = told.summary
    number = told.trial.trial if told.trial is not None else 0
    if as_json:
        record = {"trial": number, "robustness": told.robustness, "satisfied": told.robustness is not None and told.robustness > 0}
        record.update(best_trial=summary.best_trial, best_robustness=summary.best_robustness, trials=summary.trials, budget=summary.budget)
        print(json.dumps(record))
    elif told.robustness is not None:
        print(f"{told.robustness:.10g}")
    if told.trial is not None and told.trial.error:
        print(f"trial {number} failed: {told.trial.error}", file=sys.stderr)
    else:
        print(f"trial {number}: robustness {told.robustness:+.5f} ({'satisfied' if told.robustness > 0 else 'violated'})", file=sys.stderr)
    if not told.recorded:
        ahead = [entry for entry in told.waiting if entry.told is None and entry.trial < number]
        print(f"trial {number} is recorded once {handed_out(ahead)} {'is' if len(ahead) == 1 else 'are'} told", file=sys.stderr)
    left = max(summary.budget - summary.trials - len(told.waiting), 0)  # trials still to hand out (a fleet's pending ones are out)
    best = f"best so far: trial {summary.best_trial} ({summary.best_robustness:+.5f})" if summary.best_trial is not None else "no successful trial yet"
    print(f"{best}; {left} trial{'' if left == 1 else 's'} left" + (f": stlopt ask {shlex.quote(str(run_dir))}" if left > 0 else ""), file=sys.stderr)


@app.command(cls=PlainUsage)
def sweep(
    sweep_file: Path = typer.Argument(..., metavar="SWEEP_FILE", help="Sweep file (YAML): tasks, methods, seeds, variants."),
    out: Optional[Path] = typer.Option(None, "--out", help="Sweep folder (default: runs/<sweep name>)."),
    jobs: int = typer.Option(1, "--jobs", "-j", min=1, help="Cells run at once by local worker processes."),
    ray: Optional[str] = typer.Option(None, "--ray", help="Run the cells as Ray tasks: 'auto' (this machine's cluster) or a cluster address."),
) -> None:
    """Run a grid of optimisations and print the table of their results.

    Every cell (task x variant x method x seed) is an ordinary run directory in SWEEP/runs/;
    sweep.csv has one row per cell and sweep.png compares the methods. Cells already finished
    in the folder are skipped, so a killed sweep continues where it stopped. The table
    (success rate, median trials to the first satisfaction, median best robustness, wall time
    per run) goes to stdout.

    Examples:

    \b
        stlopt sweep sweeps/phi1_methods.yaml --jobs 2
        stlopt sweep sweeps/phi1_methods.yaml --ray auto
    """
    from stl_lfd.optim.runs.sweep import cell_results, open_sweep, run_sweep
    from stl_lfd.report.sweep import TABLE_HEADER, sweep_groups, table_rows, write_sweep_figure

    with user_errors():
        plan, folder = open_sweep(sweep_file, out, ray, watch_head=True)
        again = f"stlopt sweep {sweep_file}" + (f" --out {out}" if out else "")
        with (
            progress_bar(f"sweep {plan.name}", len(plan.cells)) as advance,
            user_errors(on_interrupt=f"interrupted; finished cells are kept. Continue with: {again}"),
        ):
            run_sweep(plan, folder, cell_results(jobs, ray), _cell_printer(advance, folder))
        figure = write_sweep_figure(folder)
        groups = sweep_groups(folder)
    print_table(TABLE_HEADER, table_rows(groups))
    print(f"wrote {folder / 'sweep.csv'} and {figure}", file=sys.stderr)


def _cell_printer(advance: Callable[[int], None], folder: Path) -> Callable[[Optional[CellResult], int, int], None]:
    """What a sweep shows as its cells finish: the progress bar, and a line per cell run now
    (or one for the cells already done in the folder)."""

    def finished(result: Optional[CellResult], done: int, total: int) -> None:
        advance(done)
        if result is not None:
            record = result.record
            verdict = f"satisfied at trial {record['first_satisfied_trial']}" if record["satisfied"] else "not satisfied"
            best = f"{record['best_robustness']:+.5f}" if record["best_robustness"] is not None else "-"
            print(f"{result.name}: {verdict}, best {best} ({record['wall_seconds']:.0f} s)", file=sys.stderr)
        elif done:
            print(f"{done} of {total} cells already done in {folder}", file=sys.stderr)

    return finished
