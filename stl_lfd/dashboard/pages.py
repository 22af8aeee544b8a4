"""The dashboard's pages (the folder, a run, a sweep) and the callbacks that keep them live.

Each page holds its own `dcc.Interval`, so that only the shown page's callback runs; a callback
compares the versions of the runs it shows with those the page last drew (a `dcc.Store`) and
answers "no update" when they are the same.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from dash import Input, Output, State, dcc, html
from dash.exceptions import PreventUpdate

from stl_lfd.dashboard import figures
from stl_lfd.dashboard.board import REFRESH_SECONDS, RUN_PREFIX, SWEEP_PREFIX, Dashboard, Shown
from stl_lfd.dashboard.folder import RunView, age, find, sweep_runs
from stl_lfd.sim.command import reference_path

GRAPH_STYLE = {"height": "340px"}
CELL = {"padding": "2px 12px", "textAlign": "left"}
MAX_TEXT = 500  # characters of one value read from a run's files


def _tick(name: str) -> dcc.Interval:
    return dcc.Interval(id=f"{name}-tick", interval=int(REFRESH_SECONDS * 1000))


def text(value: Any) -> str:
    """`value` as the text a page shows. Whatever a run's files hold is shown this way, never
    handed to Dash as it is: a mapping there would be rendered as a component."""
    if isinstance(value, str):
        return value
    try:
        return json.dumps(value)[:MAX_TEXT]
    except (TypeError, ValueError, RecursionError):
        return type(value).__name__


def _table(header: list[str], rows: list[list[Any]], table_id: str) -> html.Table:
    """A table whose cells are our links or text."""
    return html.Table(
        [html.Thead(html.Tr([html.Th(cell, style=CELL) for cell in header]))]
        + [html.Tbody([html.Tr([html.Td(cell if isinstance(cell, dcc.Link) else text(cell), style=CELL) for cell in row]) for row in rows])],
        id=table_id,
    )


def _best_text(view: RunView) -> str:
    best = view.best()
    if best is None:
        return "-"
    number, robustness = best
    return f"{robustness:+.5f} (trial {number}, {'satisfied' if robustness > 0 else 'violated'})"


def _run_row(board: Dashboard, entry: Shown, prefix: str = RUN_PREFIX) -> list[Any]:
    """A run's row in a table of runs, built again only when the run changed."""
    view = entry.view
    key = (view.version, view.writer())
    if entry.row is None or entry.row[0] != key:
        link = dcc.Link(view.name, href=board.address(prefix, view.path))
        try:
            budget = f" of {view.budget}" if view.budget else ""
            row = [link, str(view.path.relative_to(board.folder)), view.state(), f"{len(view.trials)}{budget}", _best_text(view)]
        except Exception as error:  # whatever the checks of `RunView` let through: one row says so
            row = [link, str(view.path.relative_to(board.folder)), f"damaged: {type(error).__name__}: {error}", "-", "-"]
        entry.row = (key, row)
    return entry.row[1]


def index_page(board: Dashboard) -> html.Div:
    return html.Div([html.H2(f"stlopt dashboard: {board.folder.name}/"), _tick("index"), dcc.Store(id="index-seen"), html.Div(id="index-content")])


def index_signature(board: Dashboard) -> tuple[list[Shown], dict[Path, int], list]:
    """The folder's runs, its sweeps with their finished cells, and what the index shows
    changes with: their paths, the runs' versions and writers, and the sweeps' cells."""
    listing = find(board.folder)
    board.listed = len(listing.runs)
    entries = [board.entry(path) for path in listing.runs]
    cells = {path: len(sweep_runs(path, board.folder)) for path in listing.sweeps}
    signature = [str(path) for path in listing.runs + listing.sweeps] + [[entry.view.version, entry.view.writer()] for entry in entries] + list(cells.values())
    return entries, cells, signature


def index_content(board: Dashboard, entries: list[Shown], cells: dict[Path, int]) -> list[Any]:
    sweep_rows = [
        [dcc.Link(path.name, href=board.address(SWEEP_PREFIX, path)), str(path.relative_to(board.folder)), f"{count} runs finished"]
        for path, count in cells.items()
    ]
    return [
        html.H3("Runs"),
        _table(["run", "folder", "state", "trials", "best robustness"], [_run_row(board, entry) for entry in entries], "runs")
        if entries
        else html.P("no run directories here yet"),
        html.H3("Sweeps"),
        _table(["sweep", "folder", "cells"], sweep_rows, "sweeps") if sweep_rows else html.P("no sweeps here"),
    ]


def run_page(board: Dashboard, path: Path) -> html.Div:
    graphs = [dcc.Graph(id=name, style=GRAPH_STYLE, config={"displaylogo": False}) for name in ("robustness", "parts", "paths")]
    return html.Div(
        [
            dcc.Link("all runs", href="/"),
            html.H2(path.name, id="run-title"),
            dcc.Store(id="run-path", data=board.relative(path)),
            dcc.Store(id="run-seen"),
            _tick("run"),
            html.Div(id="run-status"),
            html.Div(id="run-pending"),
            html.Div(graphs[:2], style={"display": "grid", "gridTemplateColumns": "1fr 1fr"}),
            html.Div([graphs[2], dcc.Graph(id="signals", config={"displaylogo": False})], style={"display": "grid", "gridTemplateColumns": "1fr 1fr"}),
            html.Div(dcc.Graph(id="tracking", style=GRAPH_STYLE), id="tracking-box", style={"display": "none"}),
        ]
    )


def run_status(view: RunView) -> html.Div:
    summary = view.summary
    budget = f" of {view.budget}" if view.budget else ""
    facts = [
        ("state", view.state()),
        ("trials", f"{len(view.trials)}{budget}"),
        ("best", _best_text(view)),
        ("unoptimised", f"{summary['initial_robustness']:+.5f}" if isinstance(summary.get("initial_robustness"), (int, float)) else "-"),
        ("spec", text(view.task.get("spec", "-"))),
        ("method", view.method),
        ("backend", text(view.task.get("backend", "-"))),
    ]
    return html.Div([html.Span([html.B(f"{name}: "), html.Span(value, id=f"run-{name}"), "   "]) for name, value in facts])


def run_pending(view: RunView) -> Any:
    waiting = [entry for entry in view.pending if not entry.get("told")]
    if not waiting:
        return None
    rows = []
    for entry in waiting:
        trial = entry.get("trial")
        reference = reference_path(view.path, trial if isinstance(trial, int) else 0)
        asked = entry.get("asked")
        rows.append(
            [
                text(trial),
                text(entry.get("robot") or "-"),
                age(asked) if isinstance(asked, (int, float)) else "-",
                str(reference.relative_to(view.path)) if reference.is_file() else "-",
            ]
        )
    return html.Div([html.H3("Handed out, waiting for tell"), _table(["trial", "robot", "asked", "reference"], rows, "pending")])


def run_outputs(board: Dashboard, path: Path, seen: Any = None) -> tuple | None:
    """What the run page shows of the run at `path` (the outputs of its callback), or None when
    the page shows it as it is already (`seen`: the run's version, and whether it was being
    written: a run's writer ends without changing a file)."""
    entry = board.entry(path)
    view = entry.view
    shown = [view.version, view.writer() is not None]
    if seen == shown:
        return None
    try:
        extras = board.extras_of(entry)
        tracking = figures.tracking_figure(view) if not view.problem else None
        return (
            run_status(view), run_pending(view), figures.robustness_figure(view), figures.parts_figure(view),
            figures.paths_figure(view, extras.regions, extras.outlines), figures.signals_figure(view, extras.thresholds),
            tracking or {}, {"display": "block" if tracking else "none"}, shown,
        )  # fmt: skip
    except Exception as error:  # whatever the checks of `RunView` let through: the page says so
        view.problem = f"cannot be drawn ({type(error).__name__}: {error})"
        return run_status(view), None, {}, {}, {}, {}, {}, {"display": "none"}, shown


def paced(started: float) -> int:
    """The page's next refresh interval (ms): the usual one, or twice the time the last answer
    took when that is longer, so that answers never queue behind each other."""
    return max(int(REFRESH_SECONDS * 1000), int(2000 * (time.perf_counter() - started)))


def sweep_page(board: Dashboard, path: Path) -> html.Div:
    return html.Div(
        [
            dcc.Link("all runs", href="/"),
            html.H2(f"sweep {path.name}"),
            dcc.Store(id="sweep-path", data=board.relative(path)),
            dcc.Store(id="sweep-seen"),
            _tick("sweep"),
            html.Div(id="sweep-content"),
        ]
    )


def register(app: Any, board: Dashboard) -> None:
    """The callbacks of the pages."""

    @app.callback(Output("page", "children"), Input("url", "pathname"))
    def route(pathname: str | None) -> Any:
        pathname = pathname if isinstance(pathname, str) else "/"
        for prefix, page, find_at in ((RUN_PREFIX, run_page, board.run_at), (SWEEP_PREFIX, sweep_page, board.sweep_at)):
            if pathname.startswith(prefix):
                path = find_at(pathname[len(prefix) :])
                if path is None:  # one answer for outside, missing and not a run alike
                    return html.Div([dcc.Link("all runs", href="/"), html.P(text(f"no such folder here: {pathname[len(prefix) :][:MAX_TEXT]}"))])
                return page(board, path)
        return index_page(board)

    @app.callback(
        Output("index-content", "children"), Output("index-seen", "data"), Output("index-tick", "interval"),
        Input("index-tick", "n_intervals"), State("index-seen", "data"),
    )  # fmt: skip
    def refresh_index(_: int, seen: Any) -> Any:
        started = time.perf_counter()
        entries, cells, signature = index_signature(board)
        if signature == seen:
            raise PreventUpdate
        return index_content(board, entries, cells), signature, paced(started)

    @app.callback(
        Output("run-status", "children"), Output("run-pending", "children"), Output("robustness", "figure"), Output("parts", "figure"),
        Output("paths", "figure"), Output("signals", "figure"), Output("tracking", "figure"), Output("tracking-box", "style"), Output("run-seen", "data"),
        Output("run-tick", "interval"), Input("run-tick", "n_intervals"), State("run-path", "data"), State("run-seen", "data"),
    )  # fmt: skip
    def refresh_run(_: int, relative: Any, seen: Any) -> Any:
        started = time.perf_counter()
        path = board.run_at(relative)  # the page's stored address, as the browser sent it back
        outputs = run_outputs(board, path, seen) if path is not None else None
        if outputs is None:
            raise PreventUpdate
        return *outputs, paced(started)

    @app.callback(
        Output("sweep-content", "children"), Output("sweep-seen", "data"), Output("sweep-tick", "interval"),
        Input("sweep-tick", "n_intervals"), State("sweep-path", "data"), State("sweep-seen", "data"),
    )  # fmt: skip
    def refresh_sweep(_: int, relative: Any, seen: Any) -> Any:
        started = time.perf_counter()
        path = board.sweep_at(relative)
        if path is None:
            raise PreventUpdate
        entries = [board.entry(run) for run in sweep_runs(path, board.folder)]
        signature = [str(entry.view.path) for entry in entries] + [entry.view.version for entry in entries]
        if signature == seen:
            raise PreventUpdate
        rows = [_run_row(board, entry) for entry in entries]
        content = [html.P(f"{len(entries)} runs finished"), _table(["run", "folder", "state", "trials", "best robustness"], rows, "cells")]
        return content, signature, paced(started)
