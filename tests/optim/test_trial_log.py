"""`trials.jsonl` read as it grows (`TrialLog`), and `RunDirectory.trials` on a log a kill cut."""

import json

import numpy as np
import pytest

from stl_lfd.errors import RunError
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.runs.lock import RunLock
from stl_lfd.optim.runs.records import trial_to_json
from stl_lfd.optim.runs.trial_log import LongLine, TrialLog
from stl_lfd.optim.trials import Trial


def line(number: int) -> str:
    trial = Trial(trial=number, phase="init", x=np.array([0.5, 0.25]), robustness=0.1 * number, status="ok")
    return json.dumps(trial_to_json(trial)) + "\n"


def test_each_read_returns_the_complete_lines_appended_since_the_last(tmp_path):
    path = tmp_path / "trials.jsonl"
    path.write_text(line(1) + "\n" + line(2) + line(3)[:20])
    log = TrialLog(path)
    assert [(entry.number, entry.record["trial"]) for entry in log.read_new()] == [(1, 1), (3, 2)]
    assert log.tail == line(3)[:20].encode() and log.offset == len(line(1) + "\n" + line(2))
    with open(path, "a") as stream:
        stream.write(line(3)[20:] + line(4))
    assert [entry.record["trial"] for entry in log.read_new()] == [3, 4]
    assert list(log.read_new()) == [] and log.tail == b"" and log.lines == 5


def test_a_reader_that_stops_at_a_bad_line_meets_it_again(tmp_path):
    path = tmp_path / "trials.jsonl"
    path.write_text(line(1) + "not json\n" + line(3))
    log = TrialLog(path)
    for entry in log.read_new():
        if entry.record is None:
            break
    assert log.lines == 1
    assert [entry.record for entry in log.read_new()][0] is None


def test_a_line_over_the_limit_is_refused_with_its_number_even_unfinished(tmp_path):
    path = tmp_path / "trials.jsonl"
    path.write_text(line(1) + "x" * 3000)
    with pytest.raises(LongLine, match="line 2: longer than"):
        list(TrialLog(path, max_line_bytes=2000).read_new())
    assert len(list(TrialLog(path).read_new())) == 1  # no limit unless asked


def test_python_s_nan_is_read(tmp_path):
    path = tmp_path / "trials.jsonl"
    path.write_text('{"trial": 1, "robustness": NaN}\n')
    assert np.isnan(next(TrialLog(path).read_new()).record["robustness"])


def run_with(tmp_path, text: str) -> RunDirectory:
    (tmp_path / "trials.jsonl").write_text(text)
    return RunDirectory(tmp_path)


def test_a_line_cut_short_is_dropped_and_removed_by_the_writer(tmp_path):
    run = run_with(tmp_path, line(1) + line(2) + line(3)[:30])
    assert [trial.trial for trial in run.trials()] == [1, 2]
    assert (tmp_path / "trials.jsonl").read_text().endswith(line(3)[:30])  # a reader leaves the file alone
    writer = RunDirectory(tmp_path, RunLock.acquire(tmp_path, tmp_path))
    assert [trial.trial for trial in writer.trials()] == [1, 2]
    assert (tmp_path / "trials.jsonl").read_text() == line(1) + line(2)


def test_a_last_line_whole_but_for_its_newline_is_kept_and_ended(tmp_path):
    run = run_with(tmp_path, line(1) + line(2).rstrip("\n"))
    writer = RunDirectory(tmp_path, RunLock.acquire(tmp_path, tmp_path))
    assert [trial.trial for trial in writer.trials()] == [1, 2]
    writer.append_trial(Trial(trial=3, phase="bo", x=np.array([0.0, 1.0]), robustness=-1.0, status="ok"), None)
    assert [trial.trial for trial in run.trials()] == [1, 2, 3]


def test_a_damaged_whole_line_is_an_error_naming_its_line(tmp_path):
    with pytest.raises(RunError, match=r"trials.jsonl:2: damaged \(not a trial record\)"):
        run_with(tmp_path, line(1) + "{}\n" + line(3)).trials()
    with pytest.raises(RunError, match=r"trials.jsonl:2: damaged \(trial 3 where trial 2 was expected\)"):
        run_with(tmp_path, line(1) + line(3)).trials()
