"""The dashboard as an attacker and a careless user meet it, through its HTTP callbacks: no
address leads outside its folder, nothing read from a run is rendered as a component, and no
damaged file (deep nesting, a FIFO, a device, a folder where a file should be) breaks a page
or the folder's list."""

import json
import os
import shutil
import threading

import numpy as np
import pytest

from stl_lfd.dashboard.app import create_app
from stl_lfd.dashboard.board import Dashboard
from stl_lfd.dashboard.figures import best_so_far_line, thinned_trials
from stl_lfd.dashboard.pages import index_content, index_signature, run_outputs
from tests.dashboard.test_pages import words

RUN_OUTPUTS = [
    ("run-status", "children"), ("run-pending", "children"), ("robustness", "figure"), ("parts", "figure"), ("paths", "figure"),
    ("signals", "figure"), ("tracking", "figure"), ("tracking-box", "style"), ("run-seen", "data"), ("run-tick", "interval"),
]  # fmt: skip
SWEEP_OUTPUTS = [("sweep-content", "children"), ("sweep-seen", "data"), ("sweep-tick", "interval")]


def callback(client, outputs, tick: str, states: list[tuple[str, object]]):
    """Post one callback request as the browser's Dash renderer does."""
    payload = {
        "output": "...".join(f"{name}.{prop}" for name, prop in outputs).join(("..", "..")),
        "outputs": [{"id": name, "property": prop} for name, prop in outputs],
        "inputs": [{"id": tick, "property": "n_intervals", "value": 1}],
        "state": [{"id": name, "property": "data", "value": value} for name, value in states],
        "changedPropIds": [f"{tick}.n_intervals"],
    }
    return client.post("/_dash-update-component", json=payload)


def route(client, pathname: str) -> str:
    payload = {
        "output": "page.children",
        "outputs": {"id": "page", "property": "children"},
        "inputs": [{"id": "url", "property": "pathname", "value": pathname}],
        "changedPropIds": ["url.pathname"],
    }
    answer = client.post("/_dash-update-component", json=payload)
    assert answer.status_code == 200
    return answer.get_data(as_text=True)


@pytest.fixture
def folders(runs_folder, tmp_path):
    """`runs/` with a run and a sweep, and beside it `outside/` with a run and a sweep of its
    own, plus a link inside `runs/` that leads to `outside/run`."""
    runs, outside = tmp_path / "runs", tmp_path / "outside"
    for folder in (runs, outside):
        shutil.copytree(runs_folder / "finished", folder / "run")
        shutil.copytree(runs_folder / "grid", folder / "grid")
    (runs / "link").symlink_to(outside / "run")
    (runs / "afile").write_text("x")
    return runs, outside


def test_no_address_from_the_browser_leads_outside_the_folder(folders):
    runs, outside = folders
    client = create_app(runs).server.test_client()
    inside = callback(client, RUN_OUTPUTS, "run-tick", [("run-path", "run"), ("run-seen", None)])
    assert inside.status_code == 200 and "finished" in inside.get_data(as_text=True)
    refused = [
        "../outside/run", str(outside / "run"), f"{runs}/../outside/run", "run/../../outside/run", "%2e%2e/outside/run", "link",
        "nothing/here", "afile", "afile/x", "", None, 7, {"a": 1}, ["run"], "run\0", "%00", "run%00", "a" * 10_000,
    ]  # fmt: skip
    answers = {callback(client, RUN_OUTPUTS, "run-tick", [("run-path", address), ("run-seen", None)]).status_code for address in refused}
    assert answers == {204}  # one answer, no update, whatever was asked: nothing read, nothing told
    sweeps = [callback(client, SWEEP_OUTPUTS, "sweep-tick", [("sweep-path", address), ("sweep-seen", None)]) for address in ("grid", "../outside/grid")]
    assert [answer.status_code for answer in sweeps] == [200, 204]
    pages = {address: route(client, "/run/" + address) for address in ("../outside/run", "link", "nothing/here", "afile/x", "%00")}
    assert all("no such folder here" in page for page in pages.values())
    assert "run-status" in route(client, "/run/run")


def test_a_link_out_of_the_folder_is_not_listed(folders):
    runs, _ = folders
    entries, cells, _ = index_signature(Dashboard(runs))
    assert [entry.view.path.name for entry in entries] == ["run"] and [path.name for path in cells] == ["grid"]


def test_what_a_run_holds_is_shown_as_text_never_as_a_component(runs_folder, tmp_path):
    run = tmp_path / "runs" / "asked"
    shutil.copytree(runs_folder / "finished", run)
    script = {"props": {"srcDoc": "<script>window.parent.hacked = 1</script>"}, "type": "Iframe", "namespace": "dash_html_components"}
    (run / "pending.json").write_text(json.dumps({"pending": [{"trial": script, "robot": script, "asked": 0.0}]}))
    client = create_app(tmp_path / "runs").server.test_client()
    answer = callback(client, RUN_OUTPUTS, "run-tick", [("run-path", "asked"), ("run-seen", None)])
    body = answer.get_json()["response"]
    pending = json.dumps(body["run-pending"]["children"])
    assert '"type": "Iframe"' not in pending and "srcDoc" in pending  # the description is there, as a string
    assert all(cell["type"] == "Td" and isinstance(cell["props"]["children"], str) for cell in _cells(body["run-pending"]["children"]))


def _cells(component) -> list:
    found = []
    if isinstance(component, dict):
        if component.get("type") == "Td":
            found.append(component)
        for value in component.get("props", {}).values():
            found += _cells(value)
    elif isinstance(component, list):
        for item in component:
            found += _cells(item)
    return found


DEEP = "[" * 1000 + "]" * 1000


@pytest.mark.parametrize(
    "name, damage",
    [
        ("deep-trials", lambda run: open(run / "trials.jsonl", "a").write(DEEP + "\n")),
        ("deep-summary", lambda run: (run / "summary.json").write_text(DEEP)),
        ("deep-pending", lambda run: (run / "pending.json").write_text(DEEP)),
        ("deep-task", lambda run: (run / "task.yaml").write_text(DEEP)),
        ("fifo-task", lambda run: ((run / "task.yaml").unlink(), os.mkfifo(run / "task.yaml"))),
        ("device-task", lambda run: ((run / "task.yaml").unlink(), (run / "task.yaml").symlink_to("/dev/zero"))),
        ("folder-trials", lambda run: ((run / "trials.jsonl").unlink(), (run / "trials.jsonl").mkdir())),
        ("no-trials", lambda run: (run / "trials.jsonl").unlink()),
        ("long-line", lambda run: open(run / "trials.jsonl", "a").write('{"trial": 6, "x": "' + "y" * 2_000_000 + '"}\n')),
    ],
)
def test_a_damaged_file_is_one_damaged_run_and_the_folder_stays_listed(runs_folder, tmp_path, name, damage):
    shutil.copytree(runs_folder / "finished", tmp_path / "runs" / "healthy")
    run = tmp_path / "runs" / name
    shutil.copytree(runs_folder / "finished", run)
    board = Dashboard(tmp_path / "runs")
    board.view(run)
    damage(run)
    answers: list = []
    reading = threading.Thread(target=lambda: answers.append((run_outputs(board, run), index_signature(board))), daemon=True)
    reading.start()
    reading.join(timeout=30)
    assert answers, "a page waited on a file"
    outputs, (entries, cells, _) = answers[0]
    assert words(outputs[0]).startswith("state: damaged: "), words(outputs[0])
    rows = words(index_content(board, entries, cells))
    assert [entry.view.path.name for entry in entries] == sorted(["healthy", name]) and rows.count("damaged:") == 1, rows


def test_the_kept_runs_are_bounded(runs_folder, tmp_path, monkeypatch):
    monkeypatch.setattr("stl_lfd.dashboard.board.MAX_SHOWN", 3)
    for index in range(5):
        shutil.copytree(runs_folder / "finished", tmp_path / "runs" / f"run{index}")
    board = Dashboard(tmp_path / "runs")
    for _ in range(2500):
        assert board.run_at("nothing/here") is None
    for index in range(5):  # shown one by one, as run pages: the last MAX_SHOWN are kept
        board.entry((tmp_path / "runs" / f"run{index}").resolve())
    assert list(board.shown) == [(tmp_path / "runs" / f"run{index}").resolve() for index in (2, 3, 4)]
    index_signature(board)  # the folder's page lists all five: all are kept, or each refresh would read them again
    assert len(board.shown) == 5


def test_a_long_run_is_thinned_for_the_screen_without_losing_its_extremes():
    generator = np.random.default_rng(0)
    numbers = np.arange(1, 200_001)
    values = generator.normal(size=numbers.size)
    values[12_345], values[150_000], values[7] = 9.0, -9.0, np.nan
    x, y = thinned_trials(numbers, values)
    assert len(x) <= 2000 and 9.0 in y and -9.0 in y and x == sorted(x)
    best_x, best_y = best_so_far_line(numbers, values)
    running = np.fmax.accumulate(np.where(np.isnan(values), -np.inf, values))
    assert best_x[-1] == 200_000 and best_y[-1] == 9.0
    assert all(round(running[number - 1], 6) == value for number, value in zip(best_x, best_y))
    assert np.all(np.diff(best_y) >= 0) and len(best_x) < 100


def test_a_run_without_trials_draws_empty_series():
    x, y = best_so_far_line(np.array([], dtype=int), np.array([]))
    assert x == [] and y == [] and thinned_trials(np.array([1]), np.array([np.nan])) == ([], [])


def test_paths_are_refused_before_anything_is_read(tmp_path):
    board = Dashboard(tmp_path)
    assert board.resolve("../" + tmp_path.name) == tmp_path.resolve()  # `..` that stays inside is the folder itself
    assert board.run_at("..") is None and board.sweep_at("/etc") is None


def test_a_sweep_whose_runs_folder_links_out_is_not_read(runs_folder, tmp_path):
    runs, outside = tmp_path / "runs", tmp_path / "outside"
    shutil.copytree(runs_folder / "grid", outside / "grid")
    (runs / "sweep").mkdir(parents=True)
    shutil.copy(runs_folder / "grid" / "sweep.yaml", runs / "sweep" / "sweep.yaml")
    (runs / "sweep" / "runs").symlink_to(outside / "grid" / "runs")
    board = Dashboard(runs)
    entries, cells, _ = index_signature(board)
    assert cells == {runs / "sweep": 0}
    client = create_app(runs).server.test_client()
    answer = callback(client, SWEEP_OUTPUTS, "sweep-tick", [("sweep-path", "sweep"), ("sweep-seen", None)])
    assert "0 runs finished" in answer.get_data(as_text=True)


def test_two_requests_drawing_one_run_while_it_grows_never_break_it(runs_folder, tmp_path):
    from stl_lfd.dashboard.figures import robustness_figure

    run = tmp_path / "runs" / "growing"
    shutil.copytree(runs_folder / "finished", run)
    board = Dashboard(tmp_path / "runs")
    view = board.entry(run.resolve()).view
    held = np.array(view.trials.robustness)  # what a figure being drawn holds
    last = json.loads((run / "trials.jsonl").read_text().splitlines()[-1])
    with open(run / "trials.jsonl", "a") as stream:
        stream.write(json.dumps(last | {"trial": 6}) + "\n")
        stream.write(json.dumps(last | {"trial": 7, "robustness": 10**400}) + "\n")  # too large for a float: damaged
    view.refresh()
    assert list(view.trials.numbers) == [1, 2, 3, 4, 5, 6] and len(view.trials.robustness) == 6 and held.size == 5
    assert view.problem and len(robustness_figure(view)["data"][0]["x"]) == 6
