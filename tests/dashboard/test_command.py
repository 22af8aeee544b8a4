"""`stlopt dashboard`'s errors: one line and a non-zero exit, before anything is served."""

import signal
import socket
import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from stl_lfd.cli import app
from tests.processes import deliverable_sigint, interrupt

runner = CliRunner()
STLOPT = str(Path(sys.executable).parent / "stlopt")


def test_a_missing_folder_is_one_line(tmp_path):
    result = runner.invoke(app, ["dashboard", str(tmp_path / "nowhere")])
    assert result.exit_code == 5
    assert result.stderr == f"error: {tmp_path / 'nowhere'}: no such folder (the dashboard shows the runs under a folder, default runs/)\n"


def test_a_port_in_use_is_one_line(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = runner.invoke(app, ["dashboard", str(tmp_path), "--port", str(port)])
    assert result.exit_code == 5
    assert result.stderr == f"error: --host 127.0.0.1 --port {port}: cannot listen there (Address already in use)\n"


def test_a_port_out_of_range_is_one_line(tmp_path):
    for port in ("-1", "70000"):
        result = runner.invoke(app, ["dashboard", str(tmp_path), "--port", port])
        assert result.exit_code == 5 and result.stderr == f"error: --port {port}: not a port (0 to 65535; 0 picks a free one)\n"


def test_addresses_are_written_as_a_browser_takes_them():
    from stl_lfd.dashboard.app import exposure, url

    assert url("::", 8050) == "http://[::]:8050/" and url("127.0.0.1", 80) == "http://127.0.0.1:80/"
    assert exposure(Path("runs"), "127.0.0.1", 8050) is None and exposure(Path("runs"), "::1", 8050) is None
    assert exposure(Path("runs"), "localhost", 8050) is None
    assert "anyone who can reach this machine on port 8050 can read the runs under runs" in exposure(Path("runs"), "0.0.0.0", 8050)


def test_every_network_is_warned_of_and_ctrl_c_says_it_stopped(tmp_path):
    command = [STLOPT, "dashboard", str(tmp_path), "--host", "0.0.0.0", "--port", "0"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=deliverable_sigint)
    try:
        warning, address = process.stderr.readline(), process.stderr.readline()
        assert warning.startswith("warning: listening on 0.0.0.0: anyone who can reach this machine") and address.startswith(
            "stlopt dashboard on http://0.0.0.0:"
        )
        _, rest = interrupt(process)
        assert process.returncode == -signal.SIGINT  # interrupted, as every command is
        assert rest == "dashboard stopped\n"
    finally:
        process.kill()
