"""`stlopt dashboard`'s errors: one line and a non-zero exit, before anything is served."""

import socket

from typer.testing import CliRunner

from stl_lfd.cli import app

runner = CliRunner()


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
