"""The `stlopt` command line. Each command parses its options and calls the library.

Data other programs read goes to stdout; messages, warnings and errors go to stderr. A user
error prints one `error: ...` line (plus the offending spec line and a caret) and exits with
the code of its class in `stl_lfd.errors`; usage errors exit 2.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import shlex
import signal
import sys
import warnings
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import Any, Iterator, Optional

import typer
from typer.core import TyperArgument, TyperCommand

from stl_lfd.allocator import keep_freed_memory
from stl_lfd.choices import SEMANTICS
from stl_lfd.errors import ConfigError, ExecutionError, ModelError, OutputError, StlLfdError
from stl_lfd.limits import MAX_RESTARTS
from stl_lfd.optim.methods import method_names
from stl_lfd.sim.registry import DEFAULT_BACKEND, backend_names, backends_help


class _PlainUsage(TyperCommand):
    """Usage lines in the usual form, `stlopt optimize [OPTIONS] TASK_FILE`, which a user can copy."""

    def collect_usage_pieces(self, ctx: typer.Context) -> list[str]:
        arguments = [param.metavar or param.name.upper() for param in self.get_params(ctx) if isinstance(param, TyperArgument)]
        return [self.options_metavar] + arguments


app = typer.Typer(
    help="Adapt demonstrated robot skills to Signal Temporal Logic requirements.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _choices(name: str, values: tuple[str, ...]) -> type[Enum]:
    """A command-line choice built from the library's own list of values (one definition)."""
    return Enum(name, [(value, value) for value in values], type=str)


SemanticsOption = _choices("SemanticsOption", SEMANTICS)
BackendOption = _choices("BackendOption", backend_names())
MethodOption = _choices("MethodOption", method_names())


def _print_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"warning: {message}", file=sys.stderr)


FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
SIGNAL_SUFFIXES = (".csv",)
INTERRUPTED = 130  # what a shell reports for a process that SIGINT ended
_as_program = False  # run as the `stlopt` program (`main`), not called in-process (tests, the API)
PLACE_HELP = "Place an object frame of the scene: NAME=x,y[,z[,yaw]] (metres, yaw in radians; z and yaw default to the scene's). Repeat for several frames."
COMMAND_HELP = "With --backend command: the executor to run, with {reference} and {signals} for the two CSV paths (no shell)."
COMMAND_TIMEOUT_HELP = "Seconds after which the executor is stopped and the trial fails (default: the task's, or 600)."

# Options that several commands share, defined once (Typer reads a parameter's default as its option).
CommandOption = typer.Option(None, "--command", help=COMMAND_HELP)
CommandTimeoutOption = typer.Option(None, "--command-timeout", help=COMMAND_TIMEOUT_HELP)
IterationsOption = typer.Option(None, "--iterations", "-N", help="Total number of trials N (default: the task's).")
InitOption = typer.Option(
    None, "--init", "-M", help="Initial trials M: scrambled Sobol points, or with method plan chosen on their plans (default: the task's)."
)
SeedOption = typer.Option(None, "--seed", help="Seed of the initial trials and of the acquisition optimiser.")


@contextmanager
def user_errors(on_interrupt: str = "interrupted") -> Iterator[None]:
    """Turn library errors into one stderr line and the error class's exit code, and Ctrl-C
    into the line `on_interrupt` and an interrupted exit (see `main`)."""
    with warnings.catch_warnings():  # restores the process's warning display afterwards
        warnings.showwarning = _print_warning
        try:
            yield
        except StlLfdError as error:
            print(f"error: {error}", file=sys.stderr)
            raise typer.Exit(code=error.exit_code) from None
        except KeyboardInterrupt:
            print(on_interrupt, file=sys.stderr)
            if _as_program:  # a second Ctrl-C while the run closes ends it by SIGINT at once, as `main` would
                signal.signal(signal.SIGINT, signal.SIG_DFL)
            raise typer.Exit(code=INTERRUPTED) from None


def main() -> None:
    """The `stlopt` program. After Ctrl-C it dies by SIGINT (not a plain exit 130), so that a
    shell loop of runs stops instead of going on to the next one."""
    global _as_program
    keep_freed_memory()
    _as_program = True
    try:
        app()
    except OSError as error:  # what no command turned into an error of its own: stdout on a full disk (/dev/full)
        where = error.filename or "cannot write the output"  # without a file name: stdout
        print(f"error: {where}: {error.strerror or error}", file=sys.stderr)
        sys.exit(OutputError.exit_code)
    except SystemExit as stop:
        if stop.code == INTERRUPTED:
            sys.stdout.flush()
            sys.stderr.flush()
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        raise


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import version

        print(f"stlopt {version('stlopt')}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version and exit."),
) -> None:
    """Adapt demonstrated robot skills to Signal Temporal Logic requirements."""


def _one_blas_thread() -> None:
    """One OpenBLAS thread for a command that does no linear algebra, unless the user chose:
    loading numpy otherwise starts one per core, which spin for a while (about 0.08 s of CPU
    on two cores, a third of a small `stlopt robustness`). Too late once numpy is loaded."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


@app.command(cls=_PlainUsage)
def robustness(
    spec: Path = typer.Argument(..., metavar="SPEC", help="STL specification file (.stl)."),
    signal_csv: str = typer.Argument(..., metavar="SIGNAL_CSV", help="Signal CSV with a time column t; '-' reads stdin."),
    semantics: SemanticsOption = typer.Option(SemanticsOption.classic, help="classic space robustness or the paper's new robustness."),
    nu: float = typer.Option(1.0, help="Sharpness of the new robustness (> 0); larger is closer to classic."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object instead of the bare number."),
) -> None:
    """Print the robustness of a recorded signal with respect to a specification.

    The robustness is the value at the first sample; it is positive exactly when the signal
    satisfies the specification. Without --json, stdout gets the number and stderr a verdict
    naming the semantics. The default is the classic robustness; 'stlopt optimize' scores
    with the new one by default (--semantics new reproduces its numbers; the verdicts agree).

    Example:

    \b
        stlopt robustness specs/example.stl examples/s1.csv --semantics new --json
    """
    _one_blas_thread()
    from stl_lfd.stl.evaluate import evaluate_file

    with user_errors():
        result = evaluate_file(spec, signal_csv, semantics.value, nu)
    if as_json:
        print(json.dumps(result.to_json()))
    else:
        print(f"{result.robustness:.10g}")
        which = "classic robustness" if semantics is SemanticsOption.classic else f"new robustness, nu = {nu:g}"
        print(f"{'satisfied' if result.satisfied else 'violated'} ({which})", file=sys.stderr)


@app.command(cls=_PlainUsage)
def learn(
    demos_dir: Path = typer.Argument(
        ..., metavar="DEMOS_DIR", help="Folder of demonstration CSVs (t,x,y,z[,...]), one CSV, or a folder of such folders (one per skill)."
    ),
    states: int = typer.Option(6, "-K", "--states", help="Number of HSMM states K."),
    restarts: int = typer.Option(1, "--restarts", min=1, max=MAX_RESTARTS, help="EM starts: k-bins, then random segmentations; the most likely model is kept."),
    output: Optional[Path] = typer.Option(
        None,
        "-o",
        "--output",
        help="Model file to write (.npz; default model.npz); for a folder of skills' folders, the folder of the models (default models).",
    ),
    sample_period: Optional[float] = typer.Option(
        None, "--sample-period", help="Resample the demos to this period in seconds (default: their median period, at most 50 Hz)."
    ),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw demos, states and retrieval into this PNG (one per skill: PLOT-SKILL.png)."),
    frames: Optional[str] = typer.Option(
        None, "--frames", help="Frames to learn in, comma-separated (default with frame sidecars: base and every frame they give)."
    ),
    min_spread: str = typer.Option(
        "auto",
        "--min-spread",
        help="Least spread of a state: POSITION,ANGLE,DURATION with units (5mm,5deg,10%); auto: that for a single demonstration, none otherwise; none.",
    ),
) -> None:
    """Learn a skill model (HSMM) from demonstrations and write the model file.

    Demonstrations with frame sidecars (demo_01.frames.yaml beside demo_01.csv: the poses of the
    objects) give a task-parameterised model (TP-HSMM) that follows the objects: learned in the
    robot base frame and in each object's frame, retrieved for new object poses.

    A folder that holds no CSV but folders of them (demos/: one folder per skill) learns every
    skill, and writes one model per skill into the -o folder (models/NAME.npz); nothing is
    written unless every skill is learned.

    Prints one row per state on stdout: mean position (base frame; for a TP-HSMM, at the
    demonstrations' first frame poses), duration mean and standard deviation in seconds, and
    the most likely successor; with several skills, one table per skill under its name.

    Examples:

    \b
        stlopt learn demos/three_regions -o three_regions.npz --plot skill.png
        stlopt learn demos/insert -o insert.npz --frames shaft,holder
        stlopt learn demos/

    One demonstration does not vary, so by itself it would give states the optimiser cannot
    move; --min-spread (auto) then widens every state to at least 5 mm and 5 degrees, and
    every duration to at least 10 % of its mean.
    """
    from stl_lfd.files import check_output_file, check_output_folder
    from stl_lfd.hsmm import demonstration_sets, summary_rows
    from stl_lfd.hsmm.spread import parse_min_spread

    with user_errors():
        sets = demonstration_sets(demos_dir)
        if sets:
            if output is not None and output.suffix.lower() == ".npz":
                raise ConfigError(
                    f"-o {output}: {demos_dir} holds one folder per skill ({', '.join(path.name for path in sets)}); -o names the folder their models go into"
                )
            folder = check_output_folder(output if output is not None else Path("models"), "models folder")
            targets = {path: folder / f"{path.name}.npz" for path in sets}
        else:
            targets = {demos_dir: check_output_file(output if output is not None else Path("model.npz"), (".npz",), "model file")}
        if plot is not None:
            check_output_file(plot, FIGURE_SUFFIXES, "figure")
        chosen = [name.strip() for name in frames.split(",")] if frames is not None else None
        floor = parse_min_spread(min_spread)
        learned = [_learned_skill(path, states, sample_period, chosen, restarts, floor) for path in targets]  # all, before any is written
        for (path, target), skill in zip(targets.items(), learned):
            if sets:
                target.parent.mkdir(parents=True, exist_ok=True)
                print(f"# {path.name}")
            _write_skill(skill, target, _skill_plot(plot, path.name) if sets else plot)
            _print_summary(summary_rows(skill.shown), skill.model.signal_names_)
            _report_learned(skill, target, states)


@dataclasses.dataclass(frozen=True)
class _LearnedSkill:
    model: Any  # HSMM or TPHSMM
    sequences: list
    shown: Any  # the model as its demonstrations show it (a TP-HSMM at their first poses)


def _learned_skill(folder: Path, states: int, sample_period: float | None, frames: list[str] | None, restarts: int, floor) -> _LearnedSkill:
    from stl_lfd.hsmm import demonstrated_skill, learn_from_folder

    model, sequences = learn_from_folder(folder, states, sample_period, frames, restarts, floor)
    return _LearnedSkill(model, sequences, demonstrated_skill(model, folder))


def _skill_plot(plot: Path | None, name: str) -> Path | None:
    """PLOT-NAME.png beside `plot`, for one of several skills."""
    return None if plot is None else plot.with_name(f"{plot.stem}-{name}{plot.suffix}")


def _write_skill(skill: _LearnedSkill, output: Path, plot: Path | None) -> None:
    from stl_lfd.files import atomic_output
    from stl_lfd.hsmm import retrieve, save_model

    save_model(skill.model, output)
    if plot is not None:
        from stl_lfd.report.skill import skill_figure

        shown = skill.shown
        figure = skill_figure(skill.sequences, shown.means_, shown.covars_, retrieve(shown).positions, skill.model.sample_period_, skill.model.signal_names_)
        with atomic_output(plot) as temporary:
            figure.savefig(temporary, dpi=110)


def _report_learned(skill: _LearnedSkill, output: Path, states: int) -> None:
    from stl_lfd.hsmm import TPHSMM

    model = skill.model
    learned_in = f", frames {', '.join(model.frame_names_)}" if isinstance(model, TPHSMM) else ""
    if model.min_spread is not None:
        spread = model.min_spread
        print(
            f"states widened to at least {1000 * spread.position:g} mm and {math.degrees(spread.angle):g} degrees, durations to {100 * spread.duration:g} % of their means (--min-spread)",
            file=sys.stderr,
        )
    count = f"{len(skill.sequences)} demonstration{'s' if len(skill.sequences) != 1 else ''}"
    print(f"wrote {output} ({count}, K = {states}{learned_in}, {len(model.monitor_.history)} EM iterations)", file=sys.stderr)


def _print_summary(rows: list[dict], names: list[str]) -> None:
    header = ["state"] + [f"{name}" for name in names] + ["duration_s", "duration_std_s", "successor"]
    print("\t".join(header))
    for row in rows:
        values = [str(row["state"])] + [f"{row['mean'][name]:.4f}" for name in names]
        values += [f"{row['duration_mean']:.3f}", f"{row['duration_std']:.3f}", str(row["successor"] or "-")]
        print("\t".join(values))


@app.command(cls=_PlainUsage)
def retrieve(
    model_file: Path = typer.Argument(..., metavar="MODEL", help="Model file written by 'stlopt learn'."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="CSV to write (default: stdout)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Seconds to retrieve (default: the model's expected duration)."),
    rate: Optional[float] = typer.Option(None, "--rate", help="Samples per second of the output (default: the model's rate)."),
    frame: list[str] = typer.Option(
        [], "--frame", help="For a model learned with frames: NAME=x,y,z[,yaw] (metres, yaw in radians), once per frame of the model."
    ),
) -> None:
    """Write the reference trajectory of a skill model as a signal CSV.

    Columns: t, the model's signals (x, y, z, ...; for a skill with orientation, qx, qy, qz, qw)
    and `state`, the HSMM state followed (1-based).
    A model learned with frames (TP-HSMM) is retrieved for the object poses given by --frame.

    Examples:

    \b
        stlopt retrieve three_regions.npz --rate 240 -o reference.csv
        stlopt retrieve in.npz --frame shaft=.45,-.25,.08 --frame holder=.6,.2,.04
    """
    from stl_lfd.files import check_output_file
    from stl_lfd.hsmm import frame_poses, load_model
    from stl_lfd.hsmm import retrieve as retrieve_trajectory
    from stl_lfd.rotations import QUATERNION_COLUMNS, ROTATION_COLUMNS
    from stl_lfd.signals import SignalTable, write_signal_csv

    with user_errors():
        if output is not None:
            check_output_file(output, SIGNAL_SUFFIXES, "signal CSV")
        model = load_model(model_file)
        poses = frame_poses(model, frame, model_file)
        try:
            trajectory = retrieve_trajectory(model, duration, rate, poses=poses)
        except ModelError as error:
            whose = "" if duration is not None else f" (its expected duration, {model.expected_duration():.3g} s)"
            raise ModelError(f"{model_file}{whose}: {error}") from None
        columns = {name: trajectory.positions[:, index] for index, name in enumerate(trajectory.signal_names) if name not in ROTATION_COLUMNS}
        if trajectory.orientations is not None:
            columns.update(zip(QUATERNION_COLUMNS, trajectory.orientations.T))
        columns["state"] = trajectory.states + 1.0
        write_signal_csv(SignalTable(trajectory.times, columns), output if output is not None else sys.stdout)
    if output is not None:
        print(f"wrote {output} ({trajectory.times.size} samples, {trajectory.times[-1]:.2f} s)", file=sys.stderr)


@app.command(cls=_PlainUsage)
def rollout(
    model_file: Path = typer.Argument(..., metavar="MODEL_OR_BEHAVIOUR", help="Model file written by 'stlopt learn', or a behaviour file (.yaml)."),
    scene: Optional[str] = typer.Option(None, help="Built-in scene name or a scene .yaml file (default: the behaviour's, or free_space)."),
    backend: BackendOption = typer.Option(BackendOption(DEFAULT_BACKEND), help=f"Execution backend ({backends_help()})."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="Signal CSV to write (default: stdout)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Seconds to execute (default: the skill's expected duration)."),
    rate: float = typer.Option(100.0, "--rate", help="Recording rate in samples per second."),
    command: Optional[str] = CommandOption,
    command_timeout: Optional[float] = CommandTimeoutOption,
    place: list[str] = typer.Option([], "--place", help=PLACE_HELP),
) -> None:
    """Execute a skill model or a behaviour once and write the recorded signals
    (t,x,y,z,gripper,force,qx,qy,qz,qw,tilt,fx,fy,fz,tx,ty,tz, then NAME_x,NAME_y,NAME_z and
    NAME_tilt for each object frame of the scene, then the outcome signals NAME_speed,
    NAME_held, NAME_depth, NAME_offset where the scene has them).

    Examples:

    \b
        stlopt rollout three_regions.npz | stlopt robustness specs/phi1.stl -
        stlopt rollout configs/behaviours/pick_insert.yaml --place holder=.6,.25
    """
    import time

    from stl_lfd.files import check_output_file
    from stl_lfd.signals import write_signal_csv
    from stl_lfd.skill import PlacedSkill

    with user_errors():
        _check_duration_and_rate(duration, rate)
        if output is not None:
            check_output_file(output, SIGNAL_SUFFIXES, "signal CSV")
        from stl_lfd.sim import BackendOptions, new_backend

        skill = PlacedSkill.load(model_file, scene, place, duration)
        reference = skill.reference()
        executor = _command(command, command_timeout, None)
        _check_command_for(backend.value, executor)
        with new_backend(backend.value, BackendOptions(command=executor)) as runner:
            capabilities = runner.capabilities
            start = time.perf_counter()
            if capabilities.simulates and reference.duration > LONG_ROLLOUT_SECONDS:
                with _progress_bar(f"simulating {reference.duration:.0f} s", int(reference.duration)) as advance:
                    result = skill.execute(runner, rate, _whole_seconds(advance), reference)
            else:
                result = skill.execute(runner, rate, reference=reference)
            elapsed = time.perf_counter() - start
        write_signal_csv(result.signals, output if output is not None else sys.stdout)
    recorded = result.signals.duration
    tracking = f"tracking error RMS {1000 * result.tracking_rms:.2f} mm, worst {1000 * result.tracking_max:.2f} mm"
    if capabilities.plays_the_plan:  # it plays the reference back: no speed or tracking to speak of
        how = f"{recorded:.2f} s of the reference played back (no dynamics)"
    elif capabilities.simulates:
        how = f"{recorded:.2f} s simulated in {elapsed:.2f} s ({recorded / max(elapsed, 1e-9):.0f}x real time); {tracking}"
    else:
        how = f"{recorded:.2f} s executed by the command in {elapsed:.2f} s; {tracking}"
    print(f"{backend.value} rollout in {skill.scene.name}: {how}" + (f"; wrote {output}" if output is not None else ""), file=sys.stderr)


LONG_ROLLOUT_SECONDS = 120.0  # simulated seconds from which a rollout shows a progress bar


def _command(text: Optional[str], timeout: Optional[float], task_command):
    """The executor command of --command/--command-timeout, None when neither is given."""
    from stl_lfd.sim import Command
    from stl_lfd.sim.command import DEFAULT_TIMEOUT

    if text is not None:
        return Command.parse(text, timeout if timeout is not None else DEFAULT_TIMEOUT, cwd=Path.cwd())
    if timeout is None:
        return None
    if task_command is None:
        raise ConfigError("--command-timeout needs a command (--command, or 'command' in the task file)")
    if not timeout > 0:
        raise ConfigError(f"--command-timeout must be positive (got {timeout:g})")
    return dataclasses.replace(task_command, timeout=float(timeout))


def _placements(scene_name: str, place: list[str]):
    """The one placement of --place options (None without any), checked against the scene."""
    if not place:
        return None
    from stl_lfd.sim.scene_file import load_scene, placement_from_options

    return (placement_from_options(load_scene(scene_name), place),)


def _check_command_for(backend: str, command) -> None:
    """ConfigError when --command is given for a backend that runs no command."""
    from stl_lfd.sim import backend_class

    if command is not None and not backend_class(backend).capabilities.needs_command:
        raise ConfigError(f"--command is for --backend command (the run's backend is {backend})")


def _whole_seconds(advance):
    """A simulation observer that reports progress once per simulated second."""
    shown = [-1]

    def observe(time: float, world: object) -> None:
        if int(time) != shown[0]:
            shown[0] = int(time)
            advance(shown[0])

    return observe


def _check_duration_and_rate(duration: Optional[float], rate: float) -> None:
    from stl_lfd.limits import samples_problem

    problem = samples_problem(duration, rate)
    if problem:
        raise ModelError(f"--duration/--rate: {problem}")


@app.command(cls=_PlainUsage)
def replay(
    source: Path = typer.Argument(
        ..., metavar="MODEL_BEHAVIOUR_OR_RUN", help="A model file, a behaviour file, or a run directory written by 'stlopt optimize'."
    ),
    trial: str = typer.Option("best", "--trial", help="For a run directory: 'best', 'initial' (the unoptimised skill) or a trial number."),
    gui: bool = typer.Option(False, "--gui", help="Show the simulator's window in real time (needs a display)."),
    backend: Optional[BackendOption] = typer.Option(None, help="Simulator to replay in (default: the run's, if it simulates; else pybullet)."),
    video: Optional[Path] = typer.Option(None, "--video", help="Record a video (.mp4 or .gif) headless."),
    spec: Optional[Path] = typer.Option(None, "--spec", help="STL spec to evaluate and whose regions to draw (a run directory knows its own)."),
    scene: Optional[str] = typer.Option(None, help="Scene (default: the run's, or free_space)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Seconds to execute (default: the run's, or the model's expected duration)."),
    semantics: Optional[SemanticsOption] = typer.Option(None, help="Semantics of the printed robustness (default: the run's, or new)."),
    place: list[str] = typer.Option([], "--place", help=PLACE_HELP + " Default: the run's (first) placement."),
) -> None:
    """Execute a skill again in a simulator and show it (GUI) or film it (video).

    Without --gui or --video, the GUI opens when a display exists; otherwise a video is
    written (replay.mp4, or replay-trial-N.mp4 inside a run directory). When a spec is known,
    the robustness of the replayed execution is printed on stdout.

    Examples:

    \b
        stlopt replay runs/phi1 --trial best --video best.mp4
        stlopt replay three_regions.npz --spec specs/phi1.stl --gui
    """

    from stl_lfd.report.replay import ReplayRequest, replay_skill

    use_gui = gui or (video is None and bool(os.environ.get("DISPLAY")))
    request = ReplayRequest(source, trial, spec, scene, duration, semantics.value if semantics else None, tuple(place), backend.value if backend else None)
    with user_errors():
        if gui and not os.environ.get("DISPLAY"):
            raise ExecutionError("--gui needs a display and DISPLAY is not set; record a video with --video FILE.mp4 instead")
        outcome = replay_skill(request, gui=use_gui, video=video, progress=_progress_bar)
    if outcome.video is not None:
        print(f"wrote {outcome.video} ({outcome.frames} frames)", file=sys.stderr)
    if outcome.robustness is not None:
        print(f"{outcome.robustness:.10g}")
        print(f"{'satisfied' if outcome.robustness > 0 else 'violated'} ({outcome.semantics} robustness of {outcome.spec})", file=sys.stderr)


@app.command(cls=_PlainUsage)
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
    place: list[str] = typer.Option([], "--place", help=PLACE_HELP + " Replaces the task's placements."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="On stderr, only what runs and the verdict (no line per trial); errors still show."),
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
        stlopt optimize --spec specs/phi2.stl
        stlopt optimize --spec my.stl --demos demos/three_regions
    """
    from stl_lfd.optim import Overrides, finish_run, resume_run, start_run
    from stl_lfd.optim.default_task import task_to_run
    from stl_lfd.optim.runs.resume import inputs_record
    from stl_lfd.progress import TrialPrinter

    with user_errors():
        file_task = task_to_run(task_file, spec, demos, model, say=lambda message: print(message, file=sys.stderr))
        given = Overrides(
            spec=spec, seed=seed, initial=init, trials=iterations, backend=backend.value if backend else None, method=method.value if method else None,
            workers=workers, command=_command(command, command_timeout, file_task.command), placements=_placements(file_task.scene, place),
        )  # fmt: skip
        run_dir = out or Path("runs") / file_task.name
        if resume:
            prepared = resume_run(run_dir, iterations, file_task, given)
        else:
            task = given.applied_to(file_task)
            _check_command_for(task.backend, given.command)
            say = (lambda message: None) if quiet else (lambda message: print(message, file=sys.stderr))
            prepared = start_run(task, run_dir, say, inputs_record(file_task, given, task))
    skill = "".join(f" {option} {path}" for option, path in (("--demos", demos), ("--model", model)) if path is not None)
    again = f"stlopt optimize {task_file or f'--spec {spec}{skill}'} --out {run_dir} --resume"
    with prepared, user_errors(on_interrupt=f"interrupted; the finished trials are kept. Continue with: {again}"):
        printer = TrialPrinter(prepared, quiet=quiet)
        try:
            summary = finish_run(prepared, printer.trial)
        finally:
            printer.stop()
        printer.done(summary)
    print(json.dumps(summary.to_json(), indent=2))


@app.command(cls=_PlainUsage)
def ask(
    target: Path = typer.Argument(..., metavar="TASK_FILE_OR_RUN", help="A task file (starts a run) or a run directory."),
    out: Optional[Path] = typer.Option(None, "--out", help="With a task file: the run directory (default: runs/<task name>)."),
    spec: Optional[Path] = typer.Option(None, "--spec", help="Use this STL spec instead of the task's (a new run only)."),
    iterations: Optional[int] = IterationsOption,
    init: Optional[int] = InitOption,
    seed: Optional[int] = SeedOption,
    method: Optional[MethodOption] = typer.Option(None, help="Optimiser method (default: the task's)."),
) -> None:
    """Hand out the next trial to execute elsewhere: write its reference CSV, print its path.

    The first ask of a task file creates the run with trial 0, the unoptimised skill. Execute
    the reference (the executor's contract is on the documentation's page on execution and
    real robots), then record the signals with 'stlopt tell'. Asking again before telling
    prints the same trial. When the run has all its trials,
    nothing is printed on stdout. The same seed gives the same trials as 'stlopt optimize'.
    References outside the scene's safety limits are recorded as failed trials, never handed out.

    Examples (then execute the printed reference and 'stlopt tell' its signals):

    \b
        stlopt ask configs/phi1.yaml --out runs/robot
        stlopt ask runs/robot
    """
    from stl_lfd.optim import Overrides, load_task
    from stl_lfd.optim.runs.asktell import ask as ask_trial
    from stl_lfd.optim.runs.asktell import ask_new
    from stl_lfd.optim.runs.resume import inputs_record

    given = Overrides(spec=spec, seed=seed, initial=init, trials=iterations, method=method.value if method else None)

    def refused(trial) -> None:
        print(f"trial {trial.trial} refused: {trial.error}", file=sys.stderr)

    with user_errors():
        if target.is_dir():
            if out is not None or set(given.given()) - {"trials"}:
                raise ConfigError(f"{target}: a run directory keeps its own settings; only --iterations may be given with it")
            run_dir, asked = target, ask_trial(target, iterations, on_refused=refused)
        else:
            file_task = load_task(target)
            run_dir = out or Path("runs") / file_task.name
            if run_dir.is_dir() and any(run_dir.iterdir()):
                asked = ask_trial(run_dir, iterations, file_task, given, on_refused=refused)
            else:
                task = given.applied_to(file_task)
                asked = ask_new(task, run_dir, inputs_record(file_task, given, task), lambda message: print(message, file=sys.stderr))
    if asked is None:
        print(f"{run_dir}: the run has all its trials (raise --iterations to extend it; stlopt report {run_dir})", file=sys.stderr)
        return
    print(asked.reference)
    what = "the unoptimised skill" if asked.trial == 0 else "an initial trial, chosen on its plan" if asked.phase == "design" else f"chosen by {asked.phase}"
    state = "still pending" if asked.again else "to execute"
    print(f"trial {asked.trial} ({what}) {state}; then: stlopt tell {shlex.quote(str(run_dir))} SIGNALS.csv", file=sys.stderr)


@app.command(cls=_PlainUsage)
def tell(
    context: typer.Context,
    run_dir: Path = typer.Argument(..., metavar="RUN_DIR", help="The run directory that 'stlopt ask' handed the trial out of."),
    signals: Optional[Path] = typer.Argument(None, metavar="SIGNALS_CSV", help="The signals recorded while executing the pending trial."),
    failed: Optional[str] = typer.Option(None, "--failed", help="Record the pending trial as failed, with this reason, instead of signals."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (trial, robustness, satisfied, best) instead of the number."),
) -> None:
    """Record the signals of the trial 'stlopt ask' handed out, and print its robustness.

    Examples:

    \b
        stlopt tell runs/robot signals.csv
        stlopt tell runs/robot --failed "protective stop at t=4 s"
    """
    from stl_lfd.optim.runs.asktell import tell as tell_trial

    if (signals is None) == (failed is None):  # mistakes in the command line itself: usage, exit 2
        context.fail("give the signals CSV of the pending trial, or --failed REASON (not both)")
    if failed is not None and not failed.strip():
        context.fail("--failed needs a reason, such as --failed 'protective stop at t = 4 s'")
    with user_errors():
        told = tell_trial(run_dir, signals, failed)
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
    left = max(summary.budget - summary.trials, 0)
    best = f"best so far: trial {summary.best_trial} ({summary.best_robustness:+.5f})" if summary.best_trial is not None else "no successful trial yet"
    print(f"{best}; {left} trial{'' if left == 1 else 's'} left" + (f": stlopt ask {shlex.quote(str(run_dir))}" if left > 0 else ""), file=sys.stderr)


@app.command(cls=_PlainUsage)
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
    from stl_lfd.files import check_output_folder
    from stl_lfd.optim.runs.sweep import local_results, ray_results, run_sweep
    from stl_lfd.optim.runs.sweep_file import load_sweep
    from stl_lfd.report.sweep import TABLE_HEADER, sweep_groups, table_rows, write_sweep_figure

    with user_errors():
        plan = load_sweep(sweep_file)
        folder = check_output_folder(out or Path("runs") / plan.name, "sweep folder")
        results = (lambda cells: ray_results(cells, ray)) if ray is not None else (lambda cells: local_results(cells, jobs))
        again = f"stlopt sweep {sweep_file}" + (f" --out {out}" if out else "")
        with (
            _progress_bar(f"sweep {plan.name}", len(plan.cells)) as advance,
            user_errors(on_interrupt=f"interrupted; finished cells are kept. Continue with: {again}"),
        ):

            def finished(result, done: int, total: int) -> None:
                advance(done)
                if result is not None:
                    record = result.record
                    verdict = f"satisfied at trial {record['first_satisfied_trial']}" if record["satisfied"] else "not satisfied"
                    best = f"{record['best_robustness']:+.5f}" if record["best_robustness"] is not None else "-"
                    print(f"{result.name}: {verdict}, best {best} ({record['wall_seconds']:.0f} s)", file=sys.stderr)
                elif done:
                    print(f"{done} of {total} cells already done in {folder}", file=sys.stderr)

            run_sweep(plan, folder, results, finished)
        figure = write_sweep_figure(folder)
        groups = sweep_groups(folder)
    _print_table(TABLE_HEADER, table_rows(groups))
    print(f"wrote {folder / 'sweep.csv'} and {figure}", file=sys.stderr)


def _print_table(header: list[str], rows: list[list[str]]) -> None:
    """A plain table on stdout: columns padded to their widest cell."""
    widths = [max(len(str(row[column])) for row in [header, *rows]) for column in range(len(header))]
    for row in [header, *rows]:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())


@app.command(cls=_PlainUsage)
def report(
    run_dir: Path = typer.Argument(..., metavar="RUN_DIR", help="Run directory written by 'stlopt optimize' (or a sweep folder)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Folder for the figures and index.html (default: RUN_DIR/report)."),
    compare: list[Path] = typer.Option([], "--compare", help="Another run directory to compare best-so-far robustness with (repeatable)."),
    gp_parameter: list[str] = typer.Option(
        [], "--gp-parameter", help="Parameter for the GP slice figure, e.g. 'mean[3].x' (repeatable; default: the two most relevant)."
    ),
) -> None:
    """Write the figures of an optimisation run (PNG) and an index.html that explains them.

    index.html: the verdict, the task (spec, what was optimised, method and budget), the
    commands to replay or continue, and each figure with its caption. Figures, where the run
    has the data: trajectories.png (paths from above and from the side), region_distances.png,
    robustness.png, components.png (each part of the spec and what they compose to),
    gp_slices.png, transitions.png (when transitions are optimised), durations.png, forces.png
    (when something was touched), tilt.png (when the hand turned), tracking.png (how the
    robot followed its plans, when the run learned it), compare.png (--compare).
    The paths of the files go to stdout. For a folder of 'stlopt sweep': its table (stdout) and
    sweep.png, redrawn from its runs.

    Example:

    \b
        stlopt report runs/phi1 --compare runs/phi1-random
    """
    from stl_lfd.report import write_report

    if (run_dir / "sweep.csv").is_file() and not (run_dir / "trials.jsonl").exists():
        _report_sweep(run_dir, out, bool(compare or gp_parameter))
        return
    with user_errors():
        index, pictures = write_report(run_dir, out, compare, gp_parameter or None)
    for path in pictures:
        print(path)
    print(index)
    print(f"wrote {len(pictures)} figures; open {index}", file=sys.stderr)


def _report_sweep(folder: Path, out: Optional[Path], run_options: bool) -> None:
    from stl_lfd.report.sweep import TABLE_HEADER, sweep_groups, table_rows, write_sweep_figure

    with user_errors():
        if out is not None or run_options:
            raise ConfigError(f"{folder}: a sweep folder's report is its table and sweep.png; --out, --compare and --gp-parameter are for run directories")
        figure = write_sweep_figure(folder)
        groups = sweep_groups(folder)
    _print_table(TABLE_HEADER, table_rows(groups))
    print(f"wrote {figure}", file=sys.stderr)


@contextmanager
def _progress_bar(description: str, total: int) -> Iterator:
    """A rich progress bar on stderr; yields a function taking the number of steps done."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as progress:
        task = progress.add_task(description, total=total)
        yield lambda done: progress.update(task, completed=done)


if __name__ == "__main__":
    main()
