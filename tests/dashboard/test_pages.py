"""What the pages show, without a browser: a run's outputs (status, pending trials, figures)
and when a page has nothing new to draw."""

import json
import shutil

from stl_lfd.dashboard.board import Dashboard
from stl_lfd.dashboard.pages import index_content, index_signature, run_outputs


def text_of(component) -> str:
    """The text a Dash component tree renders."""
    if component is None:
        return ""
    if isinstance(component, (str, int, float)):
        return str(component)
    if isinstance(component, (list, tuple)):
        return " ".join(text_of(child) for child in component)
    return text_of(getattr(component, "children", None))


def words(component) -> str:
    return " ".join(text_of(component).split())


def test_a_run_page_shows_the_run_then_waits_for_a_change(runs_folder):
    board = Dashboard(runs_folder)
    outputs = run_outputs(board, runs_folder / "finished")
    status, pending, robustness, parts, paths, signals, tracking, tracking_style, seen = outputs
    assert "state: finished" in words(status) and "trials: 5 of 5" in words(status)
    assert pending is None
    assert robustness["data"][0]["x"] == [1, 2, 3, 4, 5]
    assert {box["type"] for box in paths["layout"]["shapes"]} == {"rect"}  # the spec's regions L1-L4
    assert len(paths["layout"]["shapes"]) == 4 and [item["name"] for item in paths["data"][:2]] == ["latest (trial 5)", "best (trial 5)"]
    assert len(parts["data"]) == 4 and tracking_style == {"display": "none"}
    assert run_outputs(board, runs_folder / "finished", seen) is None  # nothing changed


def test_a_pending_trial_is_shown_with_its_robot_and_reference(runs_folder, tmp_path):
    run = tmp_path / "runs" / "asked"
    shutil.copytree(runs_folder / "finished", run)
    (run / "executions" / "trial-0006").mkdir(parents=True)
    (run / "executions" / "trial-0006" / "reference.csv").write_text("t,x,y,z\n")
    (run / "pending.json").write_text(json.dumps({"pending": [{"trial": 6, "phase": "stl", "robot": "left", "asked": 0.0}]}))
    board = Dashboard(tmp_path / "runs")
    status, pending = run_outputs(board, run)[:2]
    assert "state: waiting for tell: trial 6 (left)" in words(status)
    assert "6 left" in words(pending) and "executions/trial-0006/reference.csv" in words(pending)
    runs, sweeps, _ = index_signature(board)
    assert "waiting for tell: trial 6 (left)" in words(index_content(board, runs, sweeps))


def test_only_objects_that_moved_get_a_path():
    import numpy as np

    from stl_lfd.dashboard.figures import moved_objects
    from stl_lfd.signals import SignalTable

    times = np.linspace(0, 1, 5)
    carried = {"shaft_x": np.linspace(0.4, 0.5, 5), "shaft_y": np.zeros(5), "holder_x": np.full(5, 0.55), "holder_y": np.full(5, 0.2)}
    assert moved_objects(SignalTable(times, {"x": times, "y": times} | carried)) == ["shaft"]
