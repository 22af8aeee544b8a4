"""Skill model: learning K = 6 from five 22 s demonstrations at 100 Hz, and one retrieval of a
20 s trajectory at 240 Hz (the optimiser retrieves once per trial)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from benchmarks._timing import Row, median_seconds, print_table
from stl_lfd.hsmm import learn_from_folder, retrieve

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        for path in sorted((ROOT / "demos" / "three_regions").glob("*.csv"))[:5]:
            shutil.copy(path, folder)
        learn_seconds = median_seconds(lambda: learn_from_folder(folder, 6), repeats=3)
        model, _ = learn_from_folder(folder, 6)
    retrieve_seconds = median_seconds(lambda: retrieve(model, duration=20, rate=240), repeats=11)
    print_table(
        "Skill model (HSMM + LQT)",
        [
            Row("learn K = 6", "5 demos x 22 s at 100 Hz", learn_seconds, 2.0, f"{len(model.monitor_.history)} EM iterations"),
            Row("retrieve", "20 s at 240 Hz (4,801 samples)", retrieve_seconds, 0.030, f"model period {model.sample_period_:g} s"),
        ],
    )


if __name__ == "__main__":
    main()
