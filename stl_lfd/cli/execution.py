"""`stlopt rollout` and `stlopt replay`: execute a skill once, record it, show it or film it."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Optional

import typer

from stl_lfd.cli.options import (
    PLACE_HELP,
    SIGNAL_SUFFIXES,
    BackendOption,
    CommandOption,
    CommandTimeoutOption,
    SemanticsOption,
    check_duration_and_rate,
    command_of,
)
from stl_lfd.cli.program import PlainUsage, app, progress_bar, user_errors
from stl_lfd.errors import ExecutionError
from stl_lfd.sim.registry import DEFAULT_BACKEND, backends_help


@app.command(cls=PlainUsage)
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
    NAME_held, NAME_depth, NAME_offset (into a hole), NAME_height, NAME_dx, NAME_dy,
    NAME_offset (onto a target) where the scene has them, and the orientation
    NAME_qx, NAME_qy, NAME_qz, NAME_qw of each object the hand can carry).

    Examples:

    \b
        stlopt rollout three_regions.npz | stlopt robustness specs/phi1.stl -
        stlopt rollout configs/behaviours/pick_insert.yaml --place holder=.6,.25
    """
    from stl_lfd.files import check_output_file
    from stl_lfd.signals import write_signal_csv
    from stl_lfd.skill import PlacedSkill, timed_rollout

    with user_errors():
        check_duration_and_rate(duration, rate)
        if output is not None:
            check_output_file(output, SIGNAL_SUFFIXES, "signal CSV")
        skill = PlacedSkill.load(model_file, scene, place, duration)
        reference = skill.reference()
        executor = command_of(command, command_timeout, None)
        result, how = timed_rollout(skill, backend.value, rate, executor, reference, progress=progress_bar)
        write_signal_csv(result.signals, output if output is not None else sys.stdout)
    print(f"{backend.value} rollout in {skill.scene.name}: {how}" + (f"; wrote {output}" if output is not None else ""), file=sys.stderr)


@app.command(cls=PlainUsage)
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

    from stl_lfd.optim.runs.replay import ReplayRequest, resolve_skill
    from stl_lfd.skill.replay import replay_skill

    use_gui = gui or (video is None and bool(os.environ.get("DISPLAY")))
    request = ReplayRequest(source, trial, spec, scene, duration, semantics.value if semantics else None, tuple(place), backend.value if backend else None)
    with user_errors():
        if gui and not os.environ.get("DISPLAY"):
            raise ExecutionError("--gui needs a display and DISPLAY is not set; record a video with --video FILE.mp4 instead")
        outcome = replay_skill(resolve_skill(request), gui=use_gui, video=video, progress=progress_bar)
    if outcome.video is not None:
        print(f"wrote {outcome.video} ({outcome.frames} frames)", file=sys.stderr)
    if outcome.robustness is not None:
        print(f"{outcome.robustness:.10g}")
        print(f"{'satisfied' if outcome.robustness > 0 else 'violated'} ({outcome.semantics} robustness of {outcome.spec})", file=sys.stderr)
