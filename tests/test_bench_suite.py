"""The optimiser suite's table from records (no runs)."""

from __future__ import annotations

import json

import pytest

from benchmarks.bench_suite import HeldIndexError, main, paired_firsts, random_search, summarise


def _record(problem: str, method: str, seed: int, first: int | None) -> dict:
    return {
        "problem": problem,
        "method": method,
        "seed": seed,
        "budget": 32,
        "first_satisfied": first,
        "best_robustness": 0.01 if first else -0.01,
        "optimizer_seconds": 0.5,
        "rollout_seconds": 0.1,
    }


def test_a_records_file_of_its_own_gives_its_own_table(tmp_path):
    records = [_record("avoid", "stl", 0, 3), _record("avoid", "stl", 1, None), _record("avoid", "pi", 0, 5), _record("avoid", "pi", 1, 9)]
    path = tmp_path / "suite-other-machine.jsonl"
    path.write_text("".join(json.dumps(record) + "\n" for record in records))
    rows = {(row["problem"], row["method"]): row for row in summarise(["avoid"], ["stl", "pi"], results=path)}
    assert rows[("avoid", "stl")]["satisfied"] == "1/2" and rows[("avoid", "pi")]["satisfied"] == "2/2"
    assert rows[("avoid", "pi")]["median first"] == "7"
    assert rows[("all", "stl")]["satisfied"] == "1/2 (50 %)"  # avoid has a solution shown (results/search.jsonl)
    assert paired_firsts(["avoid"], ["stl", "pi"], results=path) == [{"reference": "stl", "against": "pi", "pairs": 1, "stl": 3, "pi": 5}]


def test_earlier_codes_records_are_tabled_under_their_label_and_never_run(tmp_path, capsys):
    records = [_record("avoid", "stl", 0, 3), _record("avoid", "stl@step6", 0, None)]
    path = tmp_path / "suite.jsonl"
    path.write_text("".join(json.dumps(record) + "\n" for record in records))
    main(["--table", "--markdown", "--problems", "avoid", "--methods", "stl", "stl@step6", "--seeds", "1", "--results", str(path)])
    assert "| avoid | 32 | +0.0023 (56.0% of 400) | stl@step6 | 0 | 0/1 |" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["--problems", "avoid", "--methods", "stl@step6", "--results", str(path)])
    assert "use it with --table" in capsys.readouterr().err
    assert path.read_text().count("\n") == 2  # nothing ran


def test_a_contact_problems_runs_are_counted_against_the_physical_check(tmp_path):
    checked = [
        _record("phi3_strict_final", "plan", 0, 1) | {"robustness": [0.01, -0.02, 0.02], "inserted": [True, False, False]},
        _record("phi3_strict_final", "plan", 1, 2) | {"robustness": [-0.01, 0.03, None], "inserted": [False, True, None]},
    ]
    path = tmp_path / "suite.jsonl"
    path.write_text("".join(json.dumps(record) + "\n" for record in checked))
    row = summarise(["phi3_strict_final"], ["plan"], results=path)[0]
    # seed 0's best (0.02) is not inserted; seed 1's (0.03) is; trial 3 of seed 0 is satisfied but not inserted
    assert row["satisfied & inserted"] == "1/2" and row["verdict agrees"] == "4/5 trials"


def test_a_directed_search_holds_its_coordinates_in_every_point():
    record = random_search("phi1_first", 3, held={0: 0.25, 5: 1.0})
    assert record["best_unit_point"][0] == 0.25 and record["best_unit_point"][5] == 1.0
    assert record["directed"] == "unit coordinates held: 0 at 0.25, 5 at 1.0"
    assert record["points"] == 3 and 0 <= record["satisfied_fraction"] <= 1


def test_a_held_coordinate_outside_the_unit_box_is_refused(capsys):
    with pytest.raises(SystemExit):
        main(["--problems", "phi1_first", "--search", "3", "--hold", "2=1.5"])
    assert "a unit coordinate is within 0 and 1" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--problems", "phi1_first", "--hold", "2=0.5"])
    assert "use it with --search N" in capsys.readouterr().err


def test_a_held_coordinate_beyond_the_problems_dimension_is_refused(capsys):
    with pytest.raises(HeldIndexError, match=r"phi1_first: --hold indices must be in 0\.\.11"):
        random_search("phi1_first", 1, held={12: 0.5})
    with pytest.raises(SystemExit):
        main(["--problems", "phi1_first", "--search", "1", "--hold", "12=0.5"])
    assert "phi1_first: --hold indices must be in 0..11" in capsys.readouterr().err
