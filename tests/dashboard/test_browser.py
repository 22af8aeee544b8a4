"""The dashboard in a real browser (Debian's Chromium, driven by Playwright): a run that another
process is extending, updated on the page within 2 s of each new trial; a click into a run and
into a sweep; a damaged run shown as such; no console errors.

With STLOPT_SCREENSHOTS=FOLDER, the screenshots of docs/dashboard.md are written there."""

import json
import os
import re
import shutil
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.optim.test_run import small_task

pytestmark = [pytest.mark.slow, pytest.mark.heavy]

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
STLOPT = str(Path(sys.executable).parent / "stlopt")
UPDATE_SECONDS = 2.0


@contextmanager
def dashboard_on(folder: Path):
    """`stlopt dashboard FOLDER` in its own process, yielding its address."""
    process = subprocess.Popen([STLOPT, "dashboard", str(folder), "--port", "0"], stderr=subprocess.PIPE, text=True)
    line = process.stderr.readline()
    match = re.search(r"http://\S+/", line)
    assert match, line + process.stderr.read()
    try:
        yield match.group(0)
    finally:
        process.terminate()
        process.wait(timeout=30)


@pytest.fixture
def dashboard_url(runs_folder):
    with dashboard_on(runs_folder) as url:
        yield url


@pytest.fixture
def page():
    from playwright.sync_api import sync_playwright

    assert Path(CHROMIUM).is_file(), "the browser test needs Debian's chromium (make test installs it)"
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.errors, page.requests = [], []
        page.on("request", lambda request: page.requests.append(request.url))
        page.on("console", lambda message: page.errors.append(message.text) if message.type == "error" else None)
        page.on("pageerror", lambda error: page.errors.append(str(error)))
        yield page
        browser.close()


def screenshot(page, name, tmp_path):
    folder = Path(os.environ.get("STLOPT_SCREENSHOTS", tmp_path))
    folder.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(folder / f"dashboard-{name}.png"), full_page=True)


def recorded(run: Path) -> int:
    trials = run / "trials.jsonl"
    return trials.read_text().count("\n") if trials.exists() else 0


def test_a_run_being_extended_shows_each_trial_within_two_seconds(runs_folder, dashboard_url, page, tmp_path, learned_model_file):
    task = small_task(tmp_path, learned_model_file)
    live = runs_folder / "live"
    extending = subprocess.Popen([STLOPT, "optimize", str(task), "--out", str(live), "-N", "80", "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        page.goto(dashboard_url)
        page.wait_for_selector("a[href='/run/live']", timeout=120_000)  # the run appears once its unoptimised trial ran
        page.click("a[href='/run/live']")
        page.wait_for_selector("#run-trials")
        seen = []
        while len(seen) < 4:
            count = recorded(live)
            while recorded(live) == count:
                assert extending.poll() is None, "the run ended before the page was watched"
                time.sleep(0.01)
            count = recorded(live)  # a new trial was recorded now
            page.wait_for_function(
                """count => parseInt(document.querySelector('#run-trials').innerText) >= count
                && document.querySelector('#robustness .js-plotly-plot').data[0].x.length >= count""",
                arg=count,
                timeout=UPDATE_SECONDS * 1000,
            )
            seen.append(count)
        assert seen == sorted(seen) and len(set(seen)) == 4
        assert page.inner_text("#run-state") == "running"
        screenshot(page, "run", tmp_path)
    finally:
        extending.terminate()
        extending.wait(timeout=60)
    page.wait_for_function("() => document.querySelector('#run-state').innerText.startsWith('stopped after')", timeout=10_000)
    assert page.errors == []


def test_the_index_a_sweep_and_a_damaged_run(runs_folder, dashboard_url, page, tmp_path):
    page.goto(dashboard_url)
    page.wait_for_selector("#runs")
    rows = page.inner_text("#runs")
    assert re.search(r"damaged\s+damaged: trials.jsonl line 6: not a trial record", rows), rows
    assert re.search(r"finished\s+finished\s+5 of 5", rows), rows
    screenshot(page, "index", tmp_path)
    page.click("a[href='/sweep/grid']")
    page.wait_for_selector("#cells")
    assert page.inner_text("#cells").count("finished") == 2
    screenshot(page, "sweep", tmp_path)
    page.click("#cells a >> nth=0")
    page.wait_for_function("() => document.querySelector('#run-state') && document.querySelector('#run-state').innerText == 'finished'")
    assert page.url.endswith("/run/grid/runs/small-random-seed0")
    page.click("text=all runs")
    page.click("a[href='/run/damaged']")
    page.wait_for_function("() => document.querySelector('#run-state') && document.querySelector('#run-state').innerText.startsWith('damaged')")
    assert page.errors == []
    assert page.requests and [url for url in page.requests if not url.startswith(dashboard_url)] == []  # nothing from elsewhere: works offline


def test_a_component_written_into_a_run_file_is_shown_as_text_and_never_runs(runs_folder, page, tmp_path):
    run = tmp_path / "runs" / "asked"
    shutil.copytree(runs_folder / "finished", run)
    frame = {"props": {"srcDoc": "<script>parent.document.title = 'script ran'</script>"}, "type": "Iframe", "namespace": "dash_html_components"}
    (run / "pending.json").write_text(json.dumps({"pending": [{"trial": 6, "phase": "stl", "robot": frame, "asked": 0.0}]}))
    with dashboard_on(tmp_path / "runs") as url:
        page.goto(url + "run/asked")
        page.wait_for_selector("#pending")
        time.sleep(1.0)  # a script would have run by now
        assert page.locator("iframe").count() == 0 and page.title() != "script ran"
        assert "Iframe" in page.inner_text("#pending") and "srcDoc" in page.inner_text("#pending")
    assert page.errors == []
