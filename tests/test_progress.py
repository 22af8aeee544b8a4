"""`optimize --quiet`: one self-overwriting progress line on a terminal, nothing of it in a pipe."""

import os
import pty
import subprocess
import sys
from pathlib import Path

from tests.conftest import ROOT

STLOPT = str(Path(sys.executable).parent / "stlopt")


def quiet_run(tmp_path, out: str) -> list[str]:
    return [STLOPT, "optimize", str(ROOT / "configs" / "phi1.yaml"), "--backend", "kinematic", "-N", "4", "-M", "2", "--quiet", "--out", str(tmp_path / out)]


def test_in_a_pipe_quiet_means_two_lines(tmp_path):
    result = subprocess.run(quiet_run(tmp_path, "piped"), capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 2 and lines[0].startswith("phi1: phi1.stl, 4 trials of method plan") and lines[1].startswith("best: trial")
    assert "\r" not in result.stderr and "\x1b" not in result.stderr


def test_on_a_terminal_quiet_shows_live_progress(tmp_path):
    pid, terminal = pty.fork()
    if pid == 0:  # the child: stlopt on the pseudo-terminal
        os.environ["COLUMNS"] = "160"
        os.execv(STLOPT, quiet_run(tmp_path, "terminal"))
    shown = b""
    while True:
        try:
            chunk = os.read(terminal, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        shown += chunk
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, shown.decode(errors="replace")
    text = shown.decode(errors="replace")
    assert "trial 1 of 4" in text and "trial 4 of 4" in text and "to go" in text and "spent" in text and "trial 5 of 4" not in text
    assert text.rfind("best: trial") > text.rfind("trial 4 of 4")  # the verdict after the progress, which is gone
