"""The dashboard's state on the server: the folder, a `RunView` for each run a page showed,
and what a run's figures draw besides its trials (`RunExtras`, read once)."""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote

import numpy as np

from stl_lfd.dashboard.folder import RunView

REFRESH_SECONDS = 0.5
RUN_PREFIX, SWEEP_PREFIX = "/run/", "/sweep/"


@dataclass
class RunExtras:
    """What a run's figures draw besides its trials, read once: the spec's regions and
    thresholds, and the outlines (seen from above) of the scene's fixed objects."""

    regions: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)
    thresholds: dict[str, list[Any]] = field(default_factory=dict)
    outlines: list[np.ndarray] = field(default_factory=list)


class Dashboard:
    """The runs under `folder`, each read by one `RunView` shared by every page that shows it."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder).resolve()
        self.views: dict[Path, RunView] = {}
        self.extras: dict[Path, tuple[int, RunExtras]] = {}  # by run: the version of its task.yaml they were read from, and them
        self.rows: dict[Path, tuple[tuple, list[Any]]] = {}  # a run's row in the tables, by its version and writer
        self.lock = threading.Lock()

    def view(self, path: Path) -> RunView:
        with self.lock:
            view = self.views.setdefault(path, RunView(path))
            view.refresh()
            return view

    def extras_of(self, view: RunView) -> RunExtras:
        known = self.extras.get(view.path)
        if known is None or known[0] != view.task_version:
            self.extras[view.path] = known = (view.task_version, run_extras(view))
        return known[1]

    def resolve(self, relative: str) -> Path | None:
        """The folder's run or sweep at `relative` (a page's address), None outside the folder
        (links inside it are followed, as `find` follows them)."""
        path = Path(os.path.normpath(self.folder / unquote(relative)))
        return path if self.inside(path) else None

    def inside(self, path: Path) -> bool:
        return path == self.folder or self.folder in path.parents

    def address(self, prefix: str, path: Path) -> str:
        return prefix + quote(str(path.relative_to(self.folder)) if path != self.folder else ".")


def run_extras(view: RunView) -> RunExtras:
    """The spec's regions and thresholds and the scene's fixed objects of a run; whatever
    cannot be read (a spec or scene moved since the run) is left out."""
    extras = RunExtras()
    try:
        from stl_lfd.report.run_data import used_regions
        from stl_lfd.stl import load_spec
        from stl_lfd.stl.thresholds import signal_thresholds

        spec = load_spec(view.spec_path())
        extras.regions, extras.thresholds = used_regions(spec), signal_thresholds(spec)  # as the report draws them
    except Exception:  # the page says what it can
        pass
    try:
        from stl_lfd.optim.runs.directory import RunDirectory
        from stl_lfd.report.objects import AXES, corners, fixed_objects, outline
        from stl_lfd.report.run_data import placed_scene_of

        task = RunDirectory.open(view.path).task()
        for item in fixed_objects(placed_scene_of(task), len(task.placements)):
            extras.outlines.append(outline(corners(item)[:, [AXES["x"], AXES["y"]]]))
    except Exception:
        pass
    return extras
