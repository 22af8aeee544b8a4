"""The `index.html` of a report: the task and its result in words, the commands that go on from
here, and the figures with their captions (the words come from `stl_lfd.report.explain`)."""

from __future__ import annotations

import html
from pathlib import Path

from stl_lfd.files import write_atomically
from stl_lfd.report import explain
from stl_lfd.report import figures as registry
from stl_lfd.report.run_data import RunData

STYLE = """body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;line-height:1.4}
table{border-collapse:collapse} th,td{text-align:left;vertical-align:top;padding:3px 10px;border-bottom:1px solid #ddd}
pre{background:#f6f6f6;padding:.6em 1em;overflow-x:auto} img{max-width:100%} figure{margin:2em 0}
figcaption{color:#444;max-width:60em} .verdict{font-size:1.15em} code{background:#f6f6f6}"""


def write_index(run: RunData, figures: list[tuple[str, Path]], out: Path) -> Path:
    """Write `out/index.html` for `run` showing `figures` (`(name, path)`, paths relative to `out`)."""
    write_atomically(out / "index.html", index_page(run, figures))
    return out / "index.html"


def index_page(run: RunData, figures: list[tuple[str, Path]]) -> str:
    escape = html.escape
    task_rows = "\n".join(f"<tr><th>{escape(key)}</th><td>{escape(value)}</td></tr>" for key, value in explain.task_rows(run))
    commands = "\n".join(f"<tr><td><code>{escape(command)}</code></td><td>{escape(what)}</td></tr>" for command, what in explain.commands(run))
    images = "\n".join(
        f'<figure id="{escape(name)}"><img src="{escape(path.name)}" alt="{escape(name)}">'
        f"<figcaption><b>{escape(path.name)}</b>: {escape(registry.figure_named(name).caption(run))}</figcaption></figure>"
        for name, path in figures
    )
    drawn = {name for name, _ in figures}
    left_out = [(f"{figure.name}.png", figure.left_out) for figure in registry.FIGURES if figure.left_out and figure.name not in drawn]
    left_out_items = "\n".join(f"<li><b>{escape(name)}</b>: {escape(why)}</li>" for name, why in left_out)
    left_out_section = f"<p>Not drawn for this run:</p><ul>\n{left_out_items}\n</ul>" if left_out else ""
    if run.missing_signals:
        left_out_section += f"<p>Missing from the run directory, so left out of every figure: {escape(', '.join(run.missing_signals))}.</p>"
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>stlopt report: {escape(run.task.name)}</title>
<style>{STYLE}</style></head>
<body><h1>{escape(run.task.name)}</h1>
<p class="verdict">{escape(explain.verdict(run))}</p>
<h2>The task</h2>
<p>Find parameters of the skill whose execution satisfies the spec {escape(run.task.spec.name)}, as robustly as possible:</p>
<pre>{escape(_spec_text(run))}</pre>
<table>
{task_rows}
</table>
<h2>Going on from here</h2>
<table>
{commands}
</table>
<h2>Figures</h2>
{images}
{left_out_section}
</body></html>
"""


def _spec_text(run: RunData) -> str:
    """The spec file as written, with its comments (`load_run` has read it already)."""
    return Path(run.task.spec).read_text().strip()
