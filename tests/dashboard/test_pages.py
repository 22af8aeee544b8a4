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


def test_damaged_files_of_every_kind_are_shown_and_never_break_a_page(runs_folder, tmp_path):
    damages = {
        "pending": ("pending.json", '{"pending": null}'),
        "optimizer": ("task.yaml", "name: x\noptimizer: cmaes\n"),
        "trial-number": ("trials.jsonl", '{"trial": "x"}\n'),
        "robustness": ("trials.jsonl", '{"trial": 1, "robustness": "bad"}\n'),
        "tracking": ("tracking.json", '{"trials": [1], "errors": {"1": {}}'),
    }
    for name, (file, text) in damages.items():
        run = tmp_path / "runs" / name
        shutil.copytree(runs_folder / "finished", run)
        (run / file).write_text(text)
    board = Dashboard(tmp_path / "runs")
    for name in damages:
        outputs = run_outputs(board, tmp_path / "runs" / name)
        state = words(outputs[0])
        if name == "tracking":  # a run whose tracking record is damaged is drawn without it
            assert "state: finished" in state and outputs[7] == {"display": "none"}
        else:
            assert "state: damaged: " in state, (name, state)
    runs, sweeps, _ = index_signature(board)
    rows = words(index_content(board, runs, sweeps))
    assert rows.count("damaged:") == 4, rows
    assert board.resolve("../../etc") is None  # the paths a page sends back are the folder's only
