"""A run's figures on the dashboard, as Plotly figure dictionaries (built without plotly's
figure classes, which cost more than the data): robustness over trials, the spec's parts over
trials, the latest and best paths with the spec's regions and the scene's objects, the signals
the spec constrains over time with its thresholds, and how the robot tracked its references."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from stl_lfd.dashboard.folder import RunView, inside
from stl_lfd.optim.trials import best_so_far
from stl_lfd.signals import SignalTable, read_signal_csv

Figure = dict[str, Any]
MAX_POINTS = 600  # samples of a drawn signal: enough for the eye, cheap to send
MAX_TRIAL_POINTS = 2000  # points of a series over trials: a run of 200,000 trials is thinned to this
MAX_PARTS = 50  # parts of the spec drawn
TIME_SIGNALS = ("force", "tilt", "shaft_tilt", "shaft_depth", "shaft_offset")  # drawn over time when recorded or constrained
LATEST, BEST = "#1f77b4", "#d62728"


def _layout(title: str, **more: Any) -> dict[str, Any]:
    return {"title": {"text": title, "font": {"size": 14}}, "margin": {"l": 50, "r": 10, "t": 36, "b": 40}, "uirevision": "keep", **more}


def label(name: str) -> str:
    """A name from a run's files as Plotly shows it as text (its `<`, `>` and `&` as entities:
    Plotly reads a few HTML tags in names)."""
    return str(name).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")[:200]


def thinned_trials(numbers: np.ndarray, values: np.ndarray, most: int = MAX_TRIAL_POINTS) -> tuple[list, list]:
    """At most about `most` points of a per-trial series for a screen: all of them when there
    are few, else the lowest and the highest value of each of `most / 2` runs of consecutive
    trials (in trial order), so that no outlier is lost. Missing values (NaN) are dropped."""
    keep = np.isfinite(values)
    numbers, values = numbers[keep], values[keep]
    if len(values) > most:
        edges = np.linspace(0, len(values), most // 2 + 1).astype(int)
        lowest = np.minimum.reduceat(values, edges[:-1])
        highest = np.maximum.reduceat(values, edges[:-1])
        picked = set()
        for start, stop, low, high in zip(edges[:-1], edges[1:], lowest, highest):
            part = values[start:stop]
            picked.update((start + int(np.argmax(part == low)), start + int(np.argmax(part == high))))
        index = np.array(sorted(picked))
        numbers, values = numbers[index], values[index]
    return numbers.tolist(), np.round(values, 6).tolist()


def best_so_far_line(numbers: np.ndarray, values: np.ndarray) -> tuple[list, list]:
    """The best robustness so far (`trials.best_so_far`) as a step line: its points where it
    improves, and the last."""
    running = best_so_far(values)
    if not len(running):
        return [], []
    changes = np.unique(np.r_[np.flatnonzero(np.r_[True, running[1:] != running[:-1]]), len(running) - 1])
    changes = changes[np.isfinite(running[changes])]
    return numbers[changes].tolist(), np.round(running[changes], 6).tolist()


def robustness_figure(view: RunView) -> Figure:
    """Each trial's robustness (thinned for the screen), the best so far, zero and the
    unoptimised skill's."""
    numbers, values = np.array(view.trials.numbers), np.array(view.trials.robustness)  # copies: a refresh may append meanwhile
    best_x, best_y = best_so_far_line(numbers, values)
    trial_x, trial_y = thinned_trials(numbers, values)
    data = [
        {"type": "scatter", "mode": "markers", "name": "trial", "x": trial_x, "y": trial_y, "marker": {"color": LATEST}},
        {"type": "scatter", "mode": "lines", "name": "best so far", "x": best_x, "y": best_y, "line": {"color": BEST, "shape": "hv"}},
    ]
    shapes = [{"type": "line", "xref": "paper", "x0": 0, "x1": 1, "y0": 0, "y1": 0, "line": {"color": "black", "width": 1}}]
    initial = view.summary.get("initial_robustness")
    if isinstance(initial, (int, float)):
        shapes.append({"type": "line", "xref": "paper", "x0": 0, "x1": 1, "y0": initial, "y1": initial, "line": {"color": "gray", "dash": "dot"}})
    return {"data": data, "layout": _layout("robustness (dotted: unoptimised; above 0: satisfied)", shapes=shapes, xaxis={"title": {"text": "trial"}})}


def parts_figure(view: RunView) -> Figure:
    """The robustness of each top-level part of the spec, trial by trial (thinned)."""
    numbers = np.array(view.trials.numbers)
    data = []
    for name, column in list(view.trials.components.items())[:MAX_PARTS]:
        x, y = thinned_trials(numbers, np.array(column)[: len(numbers)])
        data.append({"type": "scatter", "mode": "lines+markers", "name": label(name), "x": x, "y": y})
    return {"data": data, "layout": _layout("the spec's parts", xaxis={"title": {"text": "trial"}})}


def drawn_trials(view: RunView) -> dict[str, int]:
    """The trials whose executions are drawn: `latest` and `best` (0: the unoptimised skill)."""
    best = view.best()
    latest = view.trials.numbers[-1] if len(view.trials) else 0
    return {"latest": latest, "best": best[0] if best is not None else 0}


@lru_cache(maxsize=256)
def _signals(path: Path, stamp: float) -> SignalTable | None:
    try:
        return read_signal_csv(path)
    except Exception:  # a signal file being replaced, or damaged: drawn without it
        return None


def signals_of(view: RunView, trial: int) -> SignalTable | None:
    """The recorded signals of a trial of the run, when they are a file inside the run."""
    path = view.signals_path(trial)
    if not inside(path, view.path.resolve()):
        return None
    try:
        return _signals(path, path.stat().st_mtime)
    except OSError:
        return None


def _thinned(values: np.ndarray) -> list[float]:
    step = max(1, len(values) // MAX_POINTS)
    return np.round(values[::step], 5).tolist()


def moved_objects(table: SignalTable, least: float = 0.001) -> list[str]:
    """The objects whose recorded position (`NAME_x`, `NAME_y`) moved by more than `least` m."""
    names = [column[: -len("_x")] for column in table.columns if column.endswith("_x") and f"{column[:-2]}_y" in table.columns]
    return [name for name in names if max(np.ptp(table.columns[f"{name}_x"]), np.ptp(table.columns[f"{name}_y"])) > least]


def paths_figure(view: RunView, regions: dict[str, dict[str, tuple[float, float]]], outlines: list[np.ndarray]) -> Figure:
    """Seen from above: the hand's path in the latest and the best trial, a moved object's path
    (dashed), the spec's regions and the outlines of the scene's objects."""
    data = []
    for which, trial in drawn_trials(view).items():
        table = signals_of(view, trial)
        if table is None or "x" not in table.columns or "y" not in table.columns:
            continue
        color = LATEST if which == "latest" else BEST
        data.append(
            {
                "type": "scatter",
                "mode": "lines",
                "name": f"{which} (trial {trial})",
                "x": _thinned(table.columns["x"]),
                "y": _thinned(table.columns["y"]),
                "line": {"color": color},
            }
        )
        for name in moved_objects(table):
            data.append(
                {"type": "scatter", "mode": "lines", "name": label(f"{name}, {which}"), "x": _thinned(table.columns[f"{name}_x"]),
                 "y": _thinned(table.columns[f"{name}_y"]), "line": {"color": color, "dash": "dash"}}
            )  # fmt: skip
    shapes = [
        {
            "type": "rect",
            "x0": box["x"][0],
            "x1": box["x"][1],
            "y0": box["y"][0],
            "y1": box["y"][1],
            "line": {"color": "green"},
            "fillcolor": "rgba(0,160,0,0.12)",
        }
        for box in regions.values()
        if "x" in box and "y" in box
    ]
    annotations = [
        {"x": (box["x"][0] + box["x"][1]) / 2, "y": box["y"][1], "text": name, "showarrow": False, "yshift": 8}
        for name, box in regions.items()
        if "x" in box and "y" in box
    ]
    for outline in outlines:
        closed = np.vstack([outline, outline[:1]])
        data.append(
            {
                "type": "scatter",
                "mode": "lines",
                "showlegend": False,
                "hoverinfo": "skip",
                "x": closed[:, 0].tolist(),
                "y": closed[:, 1].tolist(),
                "line": {"color": "gray"},
            }
        )
    layout = _layout("paths seen from above (green: the spec's regions)", shapes=shapes, annotations=annotations, xaxis={"title": {"text": "x (m)"}})
    layout["yaxis"] = {"title": {"text": "y (m)"}, "scaleanchor": "x"}
    return {"data": data, "layout": layout}


def time_signals(view: RunView, thresholds: dict[str, list[Any]]) -> list[str]:
    """The signals drawn over time: those the spec constrains, then force and tilts where they
    vary (a kinematic rollout records them as zeros)."""
    table = signals_of(view, drawn_trials(view)["latest"])
    if table is None:
        return []
    names = [name for name in thresholds if name in table.columns and name not in ("x", "y", "z")]
    varying = [name for name in TIME_SIGNALS if name in table.columns and np.ptp(table.columns[name]) > 0]
    return names + [name for name in varying if name not in names]


def signals_figure(view: RunView, thresholds: dict[str, list[Any]]) -> Figure:
    """The signals of `time_signals` over time, one panel each, in the latest and the best
    trial, with the values the spec compares them with (dashed)."""
    names = time_signals(view, thresholds)
    data, shapes, layout = [], [], _layout("signals over time (dashed: the spec's thresholds)", height=max(240, 160 * len(names)))
    for index, name in enumerate(names):
        axis = "" if index == 0 else str(index + 1)
        low, high = 1 - (index + 1) / len(names), 1 - index / len(names)
        layout[f"yaxis{axis}"] = {"title": {"text": label(name)}, "domain": [low + 0.04, high - 0.04], "anchor": f"x{axis}"}
        layout[f"xaxis{axis}"] = {"anchor": f"y{axis}", "matches": "x" if index else None, "showticklabels": index == len(names) - 1}
        for which, trial in drawn_trials(view).items():
            table = signals_of(view, trial)
            if table is None or name not in table.columns:
                continue
            color = LATEST if which == "latest" else BEST
            data.append(
                {"type": "scatter", "mode": "lines", "name": f"{which} (trial {trial})", "legendgroup": which, "showlegend": index == 0,
                 "x": _thinned(table.times), "y": _thinned(table.columns[name]), "xaxis": f"x{axis}", "yaxis": f"y{axis}", "line": {"color": color}}
            )  # fmt: skip
        for threshold in thresholds.get(name, []):
            shapes.append(
                {
                    "type": "line",
                    "xref": f"x{axis} domain",
                    "yref": f"y{axis}",
                    "x0": 0,
                    "x1": 1,
                    "y0": threshold.value,
                    "y1": threshold.value,
                    "line": {"dash": "dash", "color": "gray"},
                }
            )
    layout["shapes"] = shapes
    if not names:
        note = {"text": "no force, tilt or object signal varies in these executions", "showarrow": False, "xref": "paper", "yref": "paper", "x": 0.5, "y": 0.5}
        layout.update(annotations=[note], xaxis={"visible": False}, yaxis={"visible": False})
    return {"data": data, "layout": layout}


def tracking_figure(view: RunView) -> Figure | None:
    """The RMS error of the plan and of the learned tracking model as predictions of each
    execution (`tracking.json`), when the run learned how its robot tracks."""
    from stl_lfd.errors import RunError
    from stl_lfd.optim.tracking_fit import TRACKING_FILE, read_tracking

    if not (view.path / TRACKING_FILE).is_file():
        return None
    try:
        record = read_tracking(view.path)
    except RunError:  # damaged, or being rewritten: the page goes without it until it reads
        return None
    if record is None or not record.errors:
        return None
    numbers = sorted(record.errors)
    data = [
        {"type": "scatter", "mode": "lines+markers", "name": name, "x": numbers, "y": [1000 * record.errors[number][column] for number in numbers]}
        for column, name in ((0, "plan"), (1, "tracking model"))
    ]
    return {"data": data, "layout": _layout("tracking: RMS error of the prediction of each execution (mm)", xaxis={"title": {"text": "trial"}})}
