"""The dashboard's costs on a folder of 100 runs (copies of one kinematic phi1 run): the time
from starting `stlopt dashboard` to its first page, the server time of the first index (every
run read), and the server time of a page update per new trial (a trial appended to one run:
the run page's outputs and the index, each written as the JSON of Dash's response).

And on one big run (200,000 trials: the kinematic run's last trial repeated with other
robustness values), through a running `stlopt dashboard` over HTTP as the browser asks: the
first answer of the run's page, the answer after each new trial, and the server's peak memory.

    python -m benchmarks.bench_dashboard [--runs 100] [--big 200000]
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from benchmarks._timing import Row, print_table

ROOT = Path(__file__).resolve().parent.parent
STLOPT = str(Path(sys.executable).parent / "stlopt")
NEW_TRIALS = 20


def one_run(folder: Path) -> Path:
    run = folder / "source"
    command = [STLOPT, "optimize", str(ROOT / "configs" / "phi1.yaml"), "--backend", "kinematic", "-N", "12", "-M", "4", "--out", str(run), "--quiet"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return run


def start_up_seconds(folder: Path) -> float:
    """From starting the command to the first answer of its page."""
    start = time.perf_counter()
    process = subprocess.Popen([STLOPT, "dashboard", str(folder), "--port", "0"], stderr=subprocess.PIPE, text=True)
    try:
        url = re.search(r"http://\S+/", process.stderr.readline()).group(0)
        urllib.request.urlopen(url, timeout=30).read()
        return time.perf_counter() - start
    finally:
        process.terminate()
        process.wait()


def appended(run: Path, number: int, last: dict | None = None) -> None:
    """Trial `number` appended to `run`, as a run records it: its signals, then its line (a
    copy of `last`, default the run's last line)."""
    last = last or json.loads((run / "trials.jsonl").read_text().splitlines()[-1])
    shutil.copy(run / "signals" / f"trial-{last['trial']:04d}.csv", run / "signals" / f"trial-{number:04d}.csv")
    with open(run / "trials.jsonl", "a") as stream:
        stream.write(json.dumps(last | {"trial": number}) + "\n")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--big", type=int, default=200_000, help="trials of the big run")
    arguments = parser.parse_args(argv)
    from dash._utils import to_json  # how Dash writes a callback's response

    from stl_lfd.dashboard import REFRESH_SECONDS, Dashboard, index_content, index_signature, run_outputs

    with tempfile.TemporaryDirectory() as scratch:
        source = one_run(Path(scratch))
        folder = Path(scratch) / "runs"
        for index in range(arguments.runs):
            shutil.copytree(source, folder / f"run-{index:03d}")
        start_up = start_up_seconds(folder)
        board = Dashboard(folder)
        start = time.perf_counter()
        index_content(board, *index_signature(board)[:2])
        first_index = time.perf_counter() - start
        watched = folder / "run-000"
        run_outputs(board, watched)  # the page as first drawn
        page_updates, index_updates = [], []
        for number in range(13, 13 + NEW_TRIALS):
            appended(watched, number)
            start = time.perf_counter()
            outputs = run_outputs(board, watched, [board.shown[watched].view.version, False])
            to_json(outputs)
            page_updates.append(time.perf_counter() - start)
            assert outputs is not None and len(board.shown[watched].view.trials) == number
            start = time.perf_counter()
            to_json(index_content(board, *index_signature(board)[:2]))
            index_updates.append(time.perf_counter() - start)
        start = time.perf_counter()
        for _ in range(10):
            index_signature(board)
        unchanged = (time.perf_counter() - start) / 10
        big = big_run_rows(source, Path(scratch) / "big", arguments.big)
    runs = f"{arguments.runs} runs"
    print_table(
        f"Dashboard ({runs} of 12 kinematic phi1 trials; update: {NEW_TRIALS} trials appended to one run, median)",
        [
            Row(
                "start-up: command to the listed runs", runs, start_up + first_index, 2.0, f"first page {start_up:.2f} s, then the listing {first_index:.2f} s"
            ),
            Row("run page update per new trial", "1 run", statistics.median(page_updates), 0.05, f"max {max(page_updates) * 1000:.0f} ms"),
            Row("index update per new trial", runs, statistics.median(index_updates), 0.05, f"max {max(index_updates) * 1000:.0f} ms"),
            Row("index refresh, nothing new", runs, unchanged, None, f"every {REFRESH_SECONDS} s while the index is open"),
            *big,
        ],
    )


RUN_OUTPUTS = [
    ("run-status", "children"), ("run-pending", "children"), ("robustness", "figure"), ("parts", "figure"), ("paths", "figure"),
    ("signals", "figure"), ("tracking", "figure"), ("tracking-box", "style"), ("run-seen", "data"), ("run-tick", "interval"),
]  # fmt: skip


def page_answer(url: str, address: str, seen: object) -> tuple[float, dict]:
    """The seconds and the response of one refresh of the run page, asked as the browser does."""
    payload = {
        "output": "...".join(f"{name}.{prop}" for name, prop in RUN_OUTPUTS).join(("..", "..")),
        "outputs": [{"id": name, "property": prop} for name, prop in RUN_OUTPUTS],
        "inputs": [{"id": "run-tick", "property": "n_intervals", "value": 1}],
        "state": [{"id": "run-path", "property": "data", "value": address}, {"id": "run-seen", "property": "data", "value": seen}],
        "changedPropIds": ["run-tick.n_intervals"],
    }
    request = urllib.request.Request(url + "_dash-update-component", json.dumps(payload).encode(), {"Content-Type": "application/json"})
    start = time.perf_counter()
    with urllib.request.urlopen(request, timeout=120) as answer:
        body = answer.read()
    return time.perf_counter() - start, json.loads(body)["response"]


def big_run(source: Path, folder: Path, trials: int) -> Path:
    """A copy of `source` whose trials.jsonl holds `trials` trials."""
    import numpy as np

    run = folder / "big"
    shutil.copytree(source, run)
    last = json.loads((run / "trials.jsonl").read_text().splitlines()[-1])
    shutil.copy(run / "signals" / f"trial-{last['trial']:04d}.csv", run / "signals" / f"trial-{trials:04d}.csv")
    values = np.random.default_rng(0).normal(-0.01, 0.01, trials)
    with open(run / "trials.jsonl", "w") as stream:
        for number, value in enumerate(values, start=1):
            stream.write(json.dumps(last | {"trial": number, "robustness": float(value)}) + "\n")
    return run


def big_run_rows(source: Path, folder: Path, trials: int) -> list[Row]:
    run = big_run(source, folder, trials)
    last = json.loads((source / "trials.jsonl").read_text().splitlines()[-1]) | {"trial": trials}
    megabytes = (run / "trials.jsonl").stat().st_size / 1e6
    process = subprocess.Popen([STLOPT, "dashboard", str(folder), "--port", "0"], stderr=subprocess.PIPE, text=True)
    try:
        url = re.search(r"http://\S+/", process.stderr.readline()).group(0)
        first, response = page_answer(url, "big", None)
        size = len(json.dumps(response)) / 1e3
        updates = []
        for number in range(trials + 1, trials + 1 + NEW_TRIALS):
            appended(run, number, last)
            seconds, response = page_answer(url, "big", response["run-seen"]["data"])
            updates.append(seconds)
        peak = _peak_megabytes(process.pid)
    finally:
        process.terminate()
        process.wait()
    size_note = f"{trials:,} trials, {megabytes:.0f} MB"
    return [
        Row("big run: first answer of its page", size_note, first, 3.0, f"{size:.0f} kB sent"),
        Row("big run: answer per new trial", size_note, statistics.median(updates), 0.1, f"max {max(updates) * 1000:.0f} ms"),
        Row("big run: server's peak memory", size_note, peak, 500.0, "the server process's VmHWM", unit="MB"),
    ]


def _peak_megabytes(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1000
    return float("nan")


if __name__ == "__main__":
    main()
