"""Signal CSV reading and writing."""

from pathlib import Path

import numpy as np
import pytest

from stl_lfd.errors import SignalError
from stl_lfd.signals import SignalTable, read_signal_csv, write_signal_csv


def test_round_trip(tmp_path: Path):
    times = np.arange(5) / 240
    table = SignalTable(times, {"x": np.linspace(0, 1, 5), "force": np.zeros(5)})
    write_signal_csv(table, tmp_path / "s.csv")
    read = read_signal_csv(tmp_path / "s.csv", required=("x",))
    assert list(read.columns) == ["x", "force"]
    np.testing.assert_allclose(read.times, times, rtol=1e-9)
    np.testing.assert_allclose(read.columns["x"], table.columns["x"], rtol=1e-9)


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "the file is empty"),
        ("t,x\n", "has a header but no samples"),
        ("x,y\n1,2\n", ":1: missing column 't' (the header has: x, y)"),
        ("t,y\n0,2\n", ":1: missing column 'x'"),
        ("t,x,x\n0,1,2\n", ":1: duplicate column 'x'"),
        ("t,x\n0,1\n1,abc\n", ":3: column 'x' has 'abc', not a number"),
        ("t,x\n0,1\n1,\n", ":3: column 'x' has '', not a number"),
        ("t,x\n0,1\n1,NaN\n", ":3: column 'x' is NaN"),
        ("t,x\n0,1\n1,2,3\n", ":3: expected 2 values, found 3"),
        ("t,x\n0,1\n0,2\n", ":3: time must be strictly increasing"),
    ],
)
def test_bad_files_name_file_and_line(tmp_path: Path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(SignalError) as caught:
        read_signal_csv(path, required=("x",))
    assert str(caught.value).startswith(str(path))
    assert message in str(caught.value)
