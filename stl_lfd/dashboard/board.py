"""The dashboard's state on the server: the folder, a `RunView` for each run a page showed
(the last `MAX_SHOWN`), and what a run's figures draw besides its trials (`RunExtras`, read
once). Every path a browser sends is resolved here and refused unless it is the folder's."""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote

import numpy as np

from stl_lfd.dashboard.folder import SWEEP_FILE, RunView, inside
from stl_lfd.optim.runs.directory import TASK_FILE

REFRESH_SECONDS = 0.5
MAX_SHOWN = 1000  # runs kept read (a few kB each, and their trials); beyond, the least recently shown are read again when shown
MAX_ADDRESS = 4096  # characters of a page's address
RUN_PREFIX, SWEEP_PREFIX = "/run/", "/sweep/"


@dataclass
class RunExtras:
    """What a run's figures draw besides its trials, read once: the spec's regions and
    thresholds, and the outlines (seen from above) of the scene's fixed objects."""

    regions: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)
    thresholds: dict[str, list[Any]] = field(default_factory=dict)
    outlines: list[np.ndarray] = field(default_factory=list)


@dataclass
class Shown:
    """One run as the server keeps it: its view, its extras (with the version of task.yaml they
    were read from), its row in the tables (with the view's version and writer), and the lock
    that lets one request at a time read it."""

    view: RunView
    extras: tuple[int, RunExtras] | None = None
    row: tuple[tuple, list[Any]] | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)


class Dashboard:
    """The runs under `folder`, each read by one `RunView` shared by every page that shows it;
    the `MAX_SHOWN` runs shown last are kept."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder).resolve()
        self.shown: OrderedDict[Path, Shown] = OrderedDict()
        self.listed = 0  # runs the folder's page lists: kept whatever MAX_SHOWN says, or each refresh would read them all again
        self.lock = threading.Lock()  # over `shown` only, never across a read

    def entry(self, path: Path) -> Shown:
        """The kept state of the run at `path`, refreshed (a read only when a file changed)."""
        with self.lock:
            entry = self.shown.get(path)
            if entry is None:
                entry = self.shown[path] = Shown(RunView(path))
                while len(self.shown) > max(MAX_SHOWN, self.listed):
                    self.shown.popitem(last=False)
            self.shown.move_to_end(path)
        with entry.lock:
            entry.view.refresh()
        return entry

    def view(self, path: Path) -> RunView:
        return self.entry(path).view

    @staticmethod
    def extras_of(entry: Shown) -> RunExtras:
        """The run's extras, read again only when its task.yaml was."""
        view = entry.view
        if entry.extras is None or entry.extras[0] != view.task_version:
            entry.extras = (view.task_version, run_extras(view))
        return entry.extras[1]

    def run_at(self, relative: Any) -> Path | None:
        """The folder's run directory at `relative` (a page's address, as the browser sent it),
        None for anything else: outside the folder once `..` and links are resolved, not a
        folder, or a folder without a run. Every refusal is the same None."""
        path = self.resolve(relative)
        return path if path is not None and os.path.lexists(path / TASK_FILE) else None

    def sweep_at(self, relative: Any) -> Path | None:
        """The folder's sweep folder at `relative`, None for anything else (as `run_at`)."""
        path = self.resolve(relative)
        return path if path is not None and (path / SWEEP_FILE).is_file() else None

    def resolve(self, relative: Any) -> Path | None:
        """The folder at `relative` under the dashboard's folder, resolved (`..` and links),
        None when it is not a folder inside it."""
        if not isinstance(relative, str) or len(relative) > MAX_ADDRESS:
            return None
        relative = unquote(relative)
        if "\0" in relative:
            return None
        path = Path(os.path.normpath(self.folder / relative.lstrip("/")))
        return path if inside(path, self.folder) and path.is_dir() else None

    def address(self, prefix: str, path: Path) -> str:
        return prefix + self.relative(path)

    def relative(self, path: Path) -> str:
        """`path`'s address under the folder (`.` for the folder itself), as a page stores it."""
        return quote(str(path.relative_to(self.folder)) if path != self.folder else ".")


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
