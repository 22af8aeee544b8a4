"""Reading and writing files safely: only regular files read, never more than a bound, and what
a killed process left half-written tidied up by the next write."""

import os
import subprocess
import threading
import time

import pytest

from stl_lfd.files import UnreadableFile, read_text, write_atomically


def test_a_fifo_is_refused_at_once_instead_of_waited_on(tmp_path):
    os.mkfifo(tmp_path / "task.yaml")
    answers = []
    reading = threading.Thread(target=lambda: answers.append(_problem(tmp_path / "task.yaml")), daemon=True)
    reading.start()
    reading.join(timeout=10)
    assert answers == ["not a regular file (a pipe, device or socket); expected a task file"]


def test_reads_are_bounded_whatever_the_file_claims(tmp_path):
    (tmp_path / "big.txt").write_text("x" * 2001)
    assert _problem(tmp_path / "big.txt", max_bytes=2000) == "the file is larger than 2 kB; is it the right task file?"
    assert read_text(tmp_path / "big.txt", "task file", max_bytes=2001) == "x" * 2001
    assert _problem("/dev/zero") == "not a regular file (a pipe, device or socket); expected a task file"
    (tmp_path / "nul.txt").write_bytes(b"a\x00b")
    assert _problem(tmp_path / "nul.txt") == "not a text file (it holds NUL bytes); expected a task file"
    assert _problem(tmp_path) == "is a folder, not a task file" and _problem(tmp_path / "none") == "no such task file"


def _problem(path, max_bytes: int = 1000) -> str:
    with pytest.raises(UnreadableFile) as error:
        read_text(path, "task file", max_bytes)
    return str(error.value)


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path):
    ended = subprocess.Popen(["true"])
    ended.wait()
    left = tmp_path / f".video.{ended.pid}.abcd_123.tmp.mp4"  # as a kill -9 mid-write leaves it
    being_written = tmp_path / f".video.{os.getpid()}.efgh_456.tmp.mp4"  # this process's own, in another thread
    other = tmp_path / ".video.backup.mp4"  # not ours
    for path in (left, being_written, other):
        path.write_text("partial")
    write_atomically(tmp_path / "video.mp4", "whole")
    assert not left.exists() and being_written.exists() and other.exists()
    assert (tmp_path / "video.mp4").read_text() == "whole"


def test_a_staging_folder_a_killed_run_left_is_removed_by_a_rerun_even_after_the_run_was_made(tmp_path):
    from stl_lfd.errors import RunError
    from stl_lfd.optim.runs.staging import ABANDONED_AFTER, StagedRun

    run = tmp_path / "run"
    (run / "signals").mkdir(parents=True)
    (run / "task.yaml").write_text("x")
    left = tmp_path / ".run.ab12cd34"
    left.mkdir()
    (left / ".lock").write_text("12345\n")
    old = time.time() - ABANDONED_AFTER - 1
    os.utime(left, (old, old))
    with pytest.raises(RunError, match="the run directory exists"):
        StagedRun(run)
    assert not left.exists()


def test_refusing_a_folder_or_a_device_leaves_no_file_open(tmp_path):
    open_before = len(os.listdir("/proc/self/fd"))
    for _ in range(20):
        for path in (tmp_path, "/dev/zero"):
            with pytest.raises(UnreadableFile):
                read_text(path, "task file")
    assert len(os.listdir("/proc/self/fd")) == open_before
