"""`stlopt dashboard`: a live, read-only view of a folder of runs and sweeps in the browser.

- `folder`: the run directories and sweep folders under a folder (`find`), and each run as it
  grows (`RunView`: new trials read incrementally, the run's state), without writing or locking.
- `figures`: the run's figures as Plotly figure dictionaries (robustness and the spec's parts
  over trials, paths with the spec's regions and the scene's objects, signals over time).
- `board`: the server's state: a `RunView` per run shown, and each run's regions, thresholds
  and object outlines, read once.
- `pages`: the pages (the folder, a run, a sweep) and the callbacks that keep them live.
- `app`: the Dash application (pages for the folder, a run and a sweep, refreshed every half
  second) and `serve`.
"""

from stl_lfd.lazy import lazy_exports

_HOMES = {
    "Dashboard": "stl_lfd.dashboard.board",
    "REFRESH_SECONDS": "stl_lfd.dashboard.board",
    "index_content": "stl_lfd.dashboard.pages",
    "index_signature": "stl_lfd.dashboard.pages",
    "run_outputs": "stl_lfd.dashboard.pages",
    "create_app": "stl_lfd.dashboard.app",
    "serve": "stl_lfd.dashboard.app",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
