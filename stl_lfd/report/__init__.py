"""Figures. Functions take arrays or a loaded run and return matplotlib Figures; `write_report`
saves a run's figures and an index.html."""

from __future__ import annotations

from pathlib import Path

from stl_lfd.errors import ConfigError
from stl_lfd.files import atomic_output, check_output_folder
from stl_lfd.optim.runs.directory import RunDirectory


def write_report(run_dir: Path, out: Path | None = None, compare: list[Path] = (), gp_parameters: list[str] | None = None) -> tuple[Path, list[Path]]:
    """Write the figures of a run directory (and of `compare` runs against it) into `out`
    (default `RUN_DIR/report`). Returns the index.html and the PNG paths."""
    import matplotlib

    matplotlib.use("Agg")
    from stl_lfd.report import figures
    from stl_lfd.report.html import write_index
    from stl_lfd.report.run_data import load_run

    out = check_output_folder(Path(out) if out is not None else Path(run_dir) / "report", "report folder")
    for path in [run_dir, *compare]:  # every run is found before any is loaded
        RunDirectory.open(path)
    run = load_run(run_dir)
    others = [load_run(path) for path in compare]
    if gp_parameters:
        unknown = [name for name in gp_parameters if name not in run.space.names]
        if unknown:
            raise ConfigError(f"--gp-parameter {unknown[0]} is not a parameter of the run ({', '.join(run.space.names)})")
    out.mkdir(parents=True, exist_ok=True)
    made = [
        ("trajectories", "End-effector paths of all trials (x-y), the best in red", figures.trajectories(run)),
        ("region_distances", "Signed distance to each region of the spec within its time window", figures.region_distances(run)),
        ("robustness", "Robustness per trial and best so far", figures.robustness_per_trial(run)),
        ("components", "Robustness of each part of the spec, or at each object placement, per trial (the lowest binds)", figures.component_robustness(run)),
        ("gp_slices", "GP surrogate through the best point", figures.gp_slices(run, gp_parameters)),
        ("transitions", "Transition graph before and after optimisation", figures.transition_graphs(run)),
        ("durations", "Duration means per state per trial", figures.durations_per_trial(run)),
        ("forces", "Contact force per trial", figures.contact_forces(run)),
        ("tilt", "The hand's tilt (angle between its approach axis and straight down) per trial", figures.tilt(run)),
    ]
    if compare:
        runs = [run] + others
        made.append(("compare", "Best so far: " + " vs ".join(str(r.path.name) for r in runs), figures.compare_runs(runs)))
    written = []
    for name, title, figure in made:
        if figure is None:
            continue
        path = out / f"{name}.png"
        with atomic_output(path) as temporary:
            figure.savefig(temporary, dpi=100)
        written.append((title, path))
    return write_index(run, written, out), [path for _, path in written]
