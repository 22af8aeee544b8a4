"""`stlopt learn` and `stlopt retrieve`: skill models from demonstrations, and their references."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional

import typer

from stl_lfd.cli.options import FIGURE_SUFFIXES, SIGNAL_SUFFIXES
from stl_lfd.cli.program import PlainUsage, app, user_errors
from stl_lfd.limits import MAX_RESTARTS

if TYPE_CHECKING:
    from stl_lfd.hsmm import LearnedSkill, SkillFiles
    from stl_lfd.hsmm.states_choice import HeldOutScore


@app.command(cls=PlainUsage)
def learn(
    demos_dir: Path = typer.Argument(
        ..., metavar="DEMOS_DIR", help="Folder of demonstration CSVs (t,x,y,z[,...]), one CSV, or a folder of such folders (one per skill)."
    ),
    states: str = typer.Option(
        "6",
        "-K",
        "--states",
        help="Number of HSMM states K; auto (2-10) or a range such as 3-8 chooses it by held-out likelihood, printing the table.",
    ),
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

    -K auto learns each K of 2-10 without one demonstration at a time and scores how likely the
    held-out demonstration is under it (log-likelihood per sample); the smallest K within one
    standard error of the best is kept. The table goes to stderr as each K is done.

    One demonstration does not vary, so by itself it would give states the optimiser cannot
    move; --min-spread (auto) then widens every state to at least 5 mm and 5 degrees, and
    every duration to at least 10 % of its mean.
    """
    from stl_lfd.files import check_output_file
    from stl_lfd.hsmm import learn_skills, skill_files
    from stl_lfd.hsmm.spread import parse_min_spread
    from stl_lfd.hsmm.states_choice import parse_states

    with user_errors():
        n_states = parse_states(states)
        files = skill_files(demos_dir, output)
        if plot is not None:
            check_output_file(plot, FIGURE_SUFFIXES, "figure")
        chosen = [name.strip() for name in frames.split(",")] if frames is not None else None
        progress = _held_out_printer(n_states) if isinstance(n_states, range) else None
        learned = learn_skills(files, n_states, sample_period, chosen, restarts, parse_min_spread(min_spread), progress)  # all, before any is written
        for skill in learned:
            _write_and_show(skill, plot)


def _held_out_printer(candidates: range) -> Callable[[SkillFiles, int, HeldOutScore | None], None]:
    """What prints the table of K on stderr as each K is done (a header before its first row)."""

    def print_row(files: SkillFiles, states: int, score: HeldOutScore | None) -> None:
        if states == candidates.start:
            print(f"{'# ' + files.name + ': ' if files.name else ''}K\theld-out log-likelihood per sample\tstandard error", file=sys.stderr)
        row = f"{score.mean:.3f}\t{score.standard_error:.3f}" if score is not None else "-\t(cannot be learned without one demonstration)"
        print(f"{states}\t{row}", file=sys.stderr, flush=True)

    return print_row


def _write_and_show(skill: LearnedSkill, plot: Path | None) -> None:
    """Write a learned skill's model file (and figure), print its states on stdout and what
    was written on stderr; with several skills, under the skill's name."""
    from stl_lfd.hsmm import summary_rows

    if skill.files.name:
        print(f"# {skill.files.name}")
    skill.save()
    figure = skill.files.figure(plot)
    if figure is not None:
        from stl_lfd.report.figures.learned import write_skill_figure

        write_skill_figure(skill, figure)
    _print_summary(summary_rows(skill.shown), skill.model.signal_names_)
    _report_learned(skill)


def _report_learned(skill: LearnedSkill) -> None:
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
    chosen = " (chosen: the smallest within one standard error of the best held-out score)" if skill.states_choice else ""
    print(f"wrote {skill.files.model} ({count}, K = {model.n_states}{chosen}{learned_in}, {len(model.monitor_.history)} EM iterations)", file=sys.stderr)


def _print_summary(rows: list[dict], names: list[str]) -> None:
    spreads = list(rows[0]["spread"]) if rows else []
    header = ["state"] + [f"{name}" for name in names] + spreads + ["duration_s", "duration_std_s", "successor"]
    print("\t".join(header))
    for row in rows:
        values = [str(row["state"])] + [f"{row['mean'][name]:.4f}" for name in names] + [f"{row['spread'][name]:.1f}" for name in spreads]
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
    from stl_lfd.hsmm import retrieve_file
    from stl_lfd.signals import write_signal_csv

    with user_errors():
        if output is not None:
            check_output_file(output, SIGNAL_SUFFIXES, "signal CSV")
        trajectory = retrieve_file(model_file, duration, rate, frame)
        write_signal_csv(trajectory.signal_table(), output if output is not None else sys.stdout)
    if output is not None:
        print(f"wrote {output} ({trajectory.times.size} samples, {trajectory.times[-1]:.2f} s)", file=sys.stderr)
