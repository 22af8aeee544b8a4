"""The dashboard's Dash application: a page for the folder (its runs and sweeps), one for a run
and one for a sweep, each refreshed every `REFRESH_SECONDS` by a callback that answers "no
update" unless a run it shows changed.

Dash (Plotly's) serves its own scripts and Plotly's from the installed packages, so the page
works offline; the server only reads the run directories.
"""

from __future__ import annotations

import ipaddress
import sys
import threading
from pathlib import Path
from typing import Any

from stl_lfd.dashboard.board import REFRESH_SECONDS, Dashboard
from stl_lfd.errors import ConfigError
from stl_lfd.spelling import spelled


def warm_up() -> None:
    """Import what the first run page needs while the server starts, in the background."""

    def imports() -> None:
        import stl_lfd.report.run_data  # noqa: F401
        import stl_lfd.stl  # noqa: F401

    threading.Thread(target=imports, name="warm-up", daemon=True).start()


def create_app(folder: Path) -> Any:
    """The Dash application of the dashboard on `folder`."""
    from dash import Dash, dcc, html

    from stl_lfd.dashboard import pages

    board = Dashboard(folder)
    app = Dash(__name__, title="stlopt dashboard", update_title=None, suppress_callback_exceptions=True, serve_locally=True)
    app.layout = html.Div(
        [
            dcc.Location(id="url"),
            dcc.Interval(id="tick", interval=int(REFRESH_SECONDS * 1000)),
            dcc.Store(id="seen"),
            html.Div(id="page", className="page"),
        ],
        style={"fontFamily": "sans-serif", "margin": "0 1.5em"},
    )
    pages.register(app, board)
    return app


def check_listenable(host: str, port: int) -> None:
    """Refuse, with one line, a port out of range or an address that cannot be listened on
    (werkzeug would print its own lines and exit)."""
    import socket

    if not 0 <= port <= 65535:
        raise ConfigError(f"{spelled('port')} {port}: not a port (0 to 65535; 0 picks a free one)")
    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind((host, port))
    except (OSError, OverflowError, UnicodeError) as error:
        raise ConfigError(f"{spelled('host')} {host} {spelled('port')} {port}: cannot listen there ({getattr(error, 'strerror', None) or error})") from None


def is_loopback(host: str) -> bool:
    """Whether `host` is only reachable from this machine (127.0.0.0/8, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def url(host: str, port: int) -> str:
    """The address to open: IPv6 addresses in brackets (`http://[::1]:8050/`)."""
    return f"http://[{host}]:{port}/" if ":" in host else f"http://{host}:{port}/"


def exposure(folder: Path, host: str, port: int) -> str | None:
    """The warning for an address other machines can reach, None for a loopback one."""
    if is_loopback(host):
        return None
    return (
        f"warning: listening on {host}: anyone who can reach this machine on port {port} can read the runs under {folder} "
        f"(no password; {spelled('host')} 127.0.0.1 keeps them on this machine)"
    )


def serve(folder: Path, host: str = "127.0.0.1", port: int = 8050, ready: Any = None) -> None:
    """Serve the dashboard until interrupted (`ready(url)` once it listens; a warning first when
    other machines can reach it); KeyboardInterrupt when interrupted."""
    import logging

    from werkzeug.serving import make_server

    check_listenable(host, port)
    app = create_app(folder)
    warm_up()
    logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no line per request on the terminal
    server = make_server(host, port, app.server, threaded=True)
    warning = exposure(folder, host, server.server_port)
    if warning is not None:
        print(warning, file=sys.stderr, flush=True)
    if ready is not None:
        ready(url(host, server.server_port))
    server.serve_forever()  # werkzeug's returns on Ctrl-C instead of raising
    raise KeyboardInterrupt
