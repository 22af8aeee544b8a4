"""The `index.html` of a report: the run's summary table and its figures."""

from __future__ import annotations

import html
from pathlib import Path

from stl_lfd.files import write_atomically
from stl_lfd.report.run_data import RunData


def summary_rows(run: RunData) -> list[tuple[str, str]]:
    summary, task = run.summary, run.task

    def number(value) -> str:
        return f"{value:+.5f}" if isinstance(value, (int, float)) else "–"

    return [
        ("run", str(run.path)),
        ("spec", f"{task.spec.name}"),
        ("semantics", task.semantics + (f" (nu = {task.nu:g})" if task.semantics == "new" else "")),
        ("backend / scene", f"{task.backend} / {task.scene}"),
        ("parameters", f"{run.space.dimension}: {', '.join(run.space.names)}"),
        ("optimiser", f"{task.optimizer.method}, {task.optimizer.initial} Sobol of {task.optimizer.trials} trials, seed {task.optimizer.seed}"),
        ("trials", f"{summary.trials} finished, {summary.failed_trials} failed"),
        ("unoptimised robustness", number(summary.initial_robustness)),
        ("best robustness", f"{number(summary.best_robustness)} (trial {summary.best_trial})"),
        ("satisfied", "yes" if summary.satisfied else "no"),
        ("first satisfied at trial", str(summary.first_satisfied_trial or "–")),
        ("wall time", f"{summary.wall_seconds:.1f} s"),
    ]


def write_index(run: RunData, figures: list[tuple[str, Path]], out: Path) -> Path:
    """Write `out/index.html` showing the summary and the figures (paths relative to `out`)."""
    rows = "\n".join(f"<tr><th>{html.escape(key)}</th><td>{html.escape(value)}</td></tr>" for key, value in summary_rows(run))
    images = "\n".join(
        f'<figure><img src="{html.escape(path.name)}" alt="{html.escape(title)}"><figcaption>{html.escape(title)}</figcaption></figure>'
        for title, path in figures
    )
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>stlopt report: {html.escape(run.task.name)}</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto;}} table{{border-collapse:collapse;}}
th,td{{text-align:left;padding:3px 10px;border-bottom:1px solid #ddd;}} img{{max-width:100%;}}
figure{{margin:2em 0;}} figcaption{{color:#555;}}</style></head>
<body><h1>{html.escape(run.task.name)}</h1>
<table>
{rows}
</table>
{images}
</body></html>
"""
    path = out / "index.html"
    write_atomically(path, page)
    return path
