from pathlib import Path

import numpy as np
import pytest
import yaml

from stl_lfd.errors import ConfigError
from stl_lfd.optim import Overrides, build_search_space, load_task
from tests.conftest import ROOT

CONFIGS = ROOT / "configs"


@pytest.mark.parametrize("name, dimension", [("phi1", 12), ("phi2", 21)])
def test_the_paper_tasks_select_the_paper_parameter_sets(name, dimension, learned_model):
    task = load_task(CONFIGS / f"{name}.yaml")
    assert task.spec == CONFIGS / ".." / "specs" / f"{name}.stl"
    assert task.optimizer.initial == 8 and task.optimizer.trials == 32 and task.optimizer.method == "plan"
    assert task.semantics == "new"
    assert build_search_space({"skill": learned_model}, task.parameters).dimension == dimension


def write_task(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "task.yaml"
    header = f"spec: {ROOT / 'specs' / 'phi1.stl'}\ndemos: {ROOT / 'demos' / 'three_regions'}\nduration: 22\n"
    path.write_text(header + body)
    return path


GOOD_PARAMETERS = "parameters:\n  means: {components: [2]}\n"


@pytest.mark.parametrize(
    "body, message",
    [
        ("parameters:\n  means: {components: [2], bta: 2}\n", "unknown key 'parameters.means.bta'"),
        ("paramters: {}\n", "unknown key 'paramters'"),
        (GOOD_PARAMETERS + "optimizer: {initial: 10, trials: 5}\n", r"'optimizer.initial' \(10\) exceeds 'optimizer.trials' \(5\)"),
        (GOOD_PARAMETERS + "optimizer: {method: ucb}\n", "'optimizer.method' must be one of stl, plan, pi, logei, random"),
        (GOOD_PARAMETERS + "optimizer: {pi: {xii: 1}}\n", "unknown key 'optimizer.pi.xii'"),
        (
            GOOD_PARAMETERS + "optimizer: {random: {seed: 1}}\n",
            r"unknown key 'optimizer.random' \(known: method, initial, trials, seed, workers, stl, plan, pi, logei\)",
        ),
        (GOOD_PARAMETERS + "optimizer: {pi: {xi: -1}}\n", "'optimizer.pi.xi' must be at least 0"),
        (GOOD_PARAMETERS + "optimizer: {pi: {restarts: 0.5}}\n", "'optimizer.pi.restarts' must be an integer"),
        (GOOD_PARAMETERS + "optimizer: {plan: {rounds: {spreads: []}}}\n", "'optimizer.plan.rounds.spreads' must be a non-empty list"),
        (GOOD_PARAMETERS + "optimizer: {xi: 0.2, pi: {xi: 0.3}}\n", "'optimizer.xi' and 'optimizer.pi.xi' both set"),
        (GOOD_PARAMETERS + "semantics: fuzzy\n", "'semantics' must be one of classic, new"),
        (GOOD_PARAMETERS + "nu: -1\n", "'nu' must be positive"),
        ("parameters:\n  means: {components: [2], beta: 0}\n", "'parameters.means.beta' must be positive"),
        ("parameters:\n  means: {components: []}\n", "'parameters.means.components' must be a non-empty list"),
        ("parameters:\n  means: {components: [2], coordinates: [w]}\n", "may hold x, y, z"),
        ("parameters:\n  transitions: sparse\n", "'parameters.transitions' must be one of none, band, full"),
        ("parameters: {}\n", "selects nothing to optimise"),
        (GOOD_PARAMETERS + "model: nowhere.npz\n", "exactly one of 'model'"),
    ],
)
def test_bad_task_files_name_the_file_and_the_key(tmp_path, body, message):
    path = write_task(tmp_path, body)
    with pytest.raises(ConfigError, match=message) as error:
        load_task(path)
    assert str(path) in str(error.value)


def test_missing_files_are_named_relative_to_the_task(tmp_path):
    path = tmp_path / "task.yaml"
    path.write_text("spec: missing.stl\ndemos: .\nduration: 22\n" + GOOD_PARAMETERS)
    with pytest.raises(ConfigError, match="'spec' names missing.stl, which does not exist"):
        load_task(path)


def test_states_beyond_the_model_are_refused(tmp_path, learned_model):
    task = load_task(write_task(tmp_path, "parameters:\n  durations: {components: [7]}\n"))
    with pytest.raises(ConfigError, match="names state 7, but the model has 6 states"):
        build_search_space({"skill": learned_model}, task.parameters, task.source)


def test_command_line_overrides_are_checked_like_the_file(tmp_path):
    task = load_task(write_task(tmp_path, GOOD_PARAMETERS))
    assert task.with_overrides(seed=4, trials=40).optimizer.seed == 4
    with pytest.raises(ConfigError, match="exceeds"):
        task.with_overrides(initial=50)


def test_the_task_as_used_reads_back_the_same(tmp_path):
    task = load_task(write_task(tmp_path, "parameters:\n  durations: {components: [2, 4], width: 0.5}\n  transitions: band\n"))
    import yaml

    again = tmp_path / "again.yaml"
    again.write_text(yaml.safe_dump(task.to_yaml_dict()))
    reread = load_task(again)
    assert reread.parameters == task.parameters and reread.optimizer == task.optimizer and reread.spec == task.spec.resolve()


def test_each_method_is_tuned_under_its_name_and_the_tuning_reads_back(tmp_path):
    import yaml

    body = GOOD_PARAMETERS + "optimizer:\n  method: pi\n  pi: {xi: 0.3, restarts: 4}\n  stl: {region: {initial: 0.5}}\n  plan: {rounds: {spreads: [0.1]}}\n"
    optimizer = load_task(write_task(tmp_path, body)).optimizer
    assert (optimizer.tuning_for("pi").xi, optimizer.tuning_for("pi").restarts, optimizer.tuning_for("pi").raw_samples) == (0.3, 4, 256)
    assert optimizer.tuning_for("stl").region.initial == 0.5 and optimizer.tuning_for("stl").region.maximum == 1.6
    assert optimizer.tuning_for("plan").rounds.spreads == (0.1,) and optimizer.tuning_for("plan").rounds.centres == 3
    assert optimizer.tuning_for("logei").restarts == 8
    written = load_task(write_task(tmp_path, body)).to_yaml_dict()["optimizer"]
    assert written["pi"] == {"xi": 0.3, "restarts": 4} and written["stl"] == {"region": {"initial": 0.5}}
    again = tmp_path / "again.yaml"
    again.write_text(yaml.safe_dump(load_task(write_task(tmp_path, body)).to_yaml_dict()))
    assert load_task(again).optimizer == optimizer


def test_the_older_spelling_of_pis_margin_is_read_as_its_setting(tmp_path):
    older = load_task(write_task(tmp_path, GOOD_PARAMETERS + "optimizer: {method: pi, xi: 0.2}\n")).optimizer
    assert older.tuning_for("pi").xi == 0.2
    assert load_task(write_task(tmp_path, GOOD_PARAMETERS + "optimizer: {xi: 0.1}\n")).optimizer.tuning == {}


def test_behaviour_tasks_take_parameters_per_skill(learned_model):
    task = load_task(CONFIGS / "phi3.yaml")
    assert set(task.parameters) == {"pick", "insert"} and task.scene == "pick_insert"
    assert task.parameters["pick"].transitions == "band" and task.parameters["insert"].means.components == (5, 6)


def test_a_scene_file_is_relative_to_the_task_file_and_survives_the_run_record(tmp_path, monkeypatch):
    import yaml

    from stl_lfd.optim import load_task

    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "s.yaml").write_text("description: a scene\nsafety: {workspace: {lower: [0.2, -0.6, 0.1], upper: [0.8, 0.6, 0.8]}, max_speed: 1}\n")
    (tmp_path / "cfg").mkdir()
    spec = Path(__file__).resolve().parents[2] / "specs" / "phi1.stl"
    demos = Path(__file__).resolve().parents[2] / "demos" / "three_regions"
    (tmp_path / "cfg" / "t.yaml").write_text(
        f"spec: {spec}\ndemos: {demos}\nscene: ../scenes/s.yaml\nduration: 22\nparameters: {{means: {{components: [2]}}}}\n"
    )
    monkeypatch.chdir(tmp_path)
    task = load_task(Path("cfg/t.yaml"))
    assert Path(task.scene) == (tmp_path / "scenes" / "s.yaml").resolve()
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "task.yaml").write_text(yaml.safe_dump(task.to_yaml_dict()))  # as a run directory keeps it
    assert load_task(Path("run/task.yaml")).scene == task.scene


def test_a_budget_below_the_initial_trials_lowers_them_for_a_new_run_with_a_note(tmp_path):
    task = load_task(write_task(tmp_path, GOOD_PARAMETERS))
    initial = task.optimizer.initial
    given, note = Overrides(trials=initial - 1).fitted_to(task)
    assert given.initial == initial - 1 and given.applied_to(task).optimizer.trials == initial - 1
    assert f"{initial - 1} is below the task's {initial} initial trials" in note and note.endswith(f"is {initial - 1} for this run")
    for unchanged in (Overrides(trials=initial), Overrides(trials=2, initial=3), Overrides(seed=1)):
        assert unchanged.fitted_to(task) == (unchanged, "")


def test_means_may_be_bounded_by_an_offset_in_metres_instead_of_standard_deviations(tmp_path, learned_model):
    task = load_task(write_task(tmp_path, "parameters:\n  means: {components: [2], offset: [-0.02, 0.03]}\n"))
    space = build_search_space({"skill": learned_model}, task.parameters, task.source)
    assert np.allclose(space.lower - space.initial, -0.02) and np.allclose(space.upper - space.initial, 0.03)
    again = tmp_path / "again.yaml"
    again.write_text(yaml.safe_dump(task.to_yaml_dict()))
    assert load_task(again).parameters == task.parameters


@pytest.mark.parametrize(
    "means, message",
    [
        ("{components: [2], offset: [0.01, 0.03]}", r"'means.offset' must be \[lower, upper\] in metres with lower <= 0 <= upper"),
        ("{components: [2], offset: [-0.01]}", "must be a list of 2 numbers"),
    ],
)
def test_an_offset_that_makes_no_sense_is_refused(tmp_path, means, message):
    with pytest.raises(ConfigError, match=message):
        load_task(write_task(tmp_path, f"parameters:\n  means: {means}\n"))
