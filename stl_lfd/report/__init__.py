"""Reports. `write_report` saves a run's figures (`figures`: one `FigureSpec` per figure, in a
registry: a loaded run in, a matplotlib Figure and its caption out) and an index.html that
explains them (`html`, with the run's words from `explain`)."""

from __future__ import annotations

from pathlib import Path

from stl_lfd.errors import ConfigError
from stl_lfd.files import check_output_folder
from stl_lfd.lazy import lazy_exports
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.spelling import spelled

_HOMES = {"followed_states": "stl_lfd.report.figures.skills", "load_run": "stl_lfd.report.run_data"}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
__all__ += ["write_report"]


def write_report(run_dir: Path, out: Path | None = None, compare: list[Path] = (), gp_parameters: list[str] | None = None) -> tuple[Path, list[Path]]:
    """Write the figures of a run directory (and of `compare` runs against it) into `out`
    (default `RUN_DIR/report`). Returns the index.html and the PNG paths."""
    import matplotlib

    matplotlib.use("Agg")
    from stl_lfd.report import figures
    from stl_lfd.report.figures import ReportOptions
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
            raise ConfigError(f"{spelled('gp_parameters')} {unknown[0]} is not a parameter of the run ({', '.join(run.space.names)})")
    out.mkdir(parents=True, exist_ok=True)
    options = ReportOptions(tuple(others), tuple(gp_parameters) if gp_parameters else None)
    written = []
    for spec in figures.FIGURES:
        path = out / f"{spec.name}.png"
        if not spec.applies(run, options):
            path.unlink(missing_ok=True)  # an earlier report's, no longer true
            continue
        figures.save_figure(spec.draw(run, options), path)
        written.append((spec.name, path))
    return write_index(run, written, out), [path for _, path in written]
