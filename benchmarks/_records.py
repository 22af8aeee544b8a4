"""Shared helpers of the benchmarks that record runs as JSON lines: seed ranges, the commit, and
running jobs (side by side if asked) while each finished one is appended to the records."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

ROOT = Path(__file__).resolve().parent.parent


def seed_list(text: str) -> list[int]:
    """`0-9`, `3`, or `0-4,7` as a list of seeds."""
    seeds = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        seeds.extend(range(int(first), int(last or first) + 1))
    return seeds


def commit() -> str:
    """The checked-out commit, short; `unknown` outside a git work tree."""
    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def recorded_results(run: Callable[[Any], dict[str, Any]], jobs: Sequence[Any], processes: int, out: Path, stamp: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """`run(job)` for every job (in `processes` spawned processes when more than 1), each result
    with `stamp` in front appended to `out` as one JSON line as it finishes, and yielded."""
    if processes > 1:
        from stl_lfd.optim import local_map

        finished = (result for _, result in local_map(run, list(jobs), processes))
    else:
        finished = (run(job) for job in jobs)
    out.parent.mkdir(parents=True, exist_ok=True)
    for result in finished:
        line = stamp | result
        with open(out, "a") as stream:
            stream.write(json.dumps(line) + "\n")
        yield line
