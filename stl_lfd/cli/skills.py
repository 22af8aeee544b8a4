"""`stlopt learn` and `stlopt retrieve`: skill models from demonstrations, and their references."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path
from typing import Any, Optional

import typer

from stl_lfd.cli.options import FIGURE_SUFFIXES, SIGNAL_SUFFIXES
from stl_lfd.cli.program import PlainUsage, app, user_errors
from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.limits import MAX_RESTARTS


@app.command(cls=PlainUsage)
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
    from stl_lfd.hsmm import retrieve, save_model

    save_model(skill.model, output)
    if plot is not None:
        from stl_lfd.report.figures import LEARNED_SKILL, SkillDrawing, save_figure

        shown, model = skill.shown, skill.model
        drawing = SkillDrawing(skill.sequences, shown.means_, shown.covars_, retrieve(shown).positions, model.sample_period_, model.signal_names_)
        save_figure(LEARNED_SKILL.draw(drawing), plot, dpi=110)


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


@app.command(cls=PlainUsage)
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
