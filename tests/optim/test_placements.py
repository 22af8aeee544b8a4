"""Optimising object-centric skills: means in a frame, object placements, the worst over them."""

import json
from pathlib import Path

import numpy as np
import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.hsmm import learn_from_folder, save_model
from stl_lfd.optim import finish_run, load_task, start_run
from tests.conftest import ROOT

BEHAVIOUR = ROOT / "configs" / "behaviours" / "pick_insert.yaml"
PLACEMENTS = """placements:
  - {shaft: [0.42, -0.22], holder: {position: [0.52, 0.24, 0.04], yaw: 0.3}}
  - {shaft: [0.48, -0.28], holder: [0.60, 0.16, 0.04, -0.3]}
"""


@pytest.fixture(scope="module")
def behaviour_models():
    from stl_lfd.optim.inputs import resolve, task_models

    return task_models(resolve(load_task(placed_task(Path(__import__("tempfile").mkdtemp())))))


def phi1_task(tmp_path: Path, model: Path, frame: str = "") -> Path:
    path = tmp_path / f"phi1-{model.stem}.yaml"
    path.write_text(
        f"spec: {ROOT / 'specs' / 'phi1.stl'}\nmodel: {model}\nbackend: kinematic\nduration: 22\nrate: 50\n"
        f"parameters:\n  means: {{components: [2, 3]{frame}}}\n  durations: {{components: all}}\n"
        "optimizer: {initial: 3, trials: 5, seed: 4}\n"
    )
    return path


@pytest.mark.slow
def test_a_model_with_the_base_frame_alone_gives_the_same_trials_as_the_plain_model(tmp_path):
    folder = ROOT / "demos" / "three_regions"
    save_model(learn_from_folder(folder, 6)[0], tmp_path / "plain.npz")
    save_model(learn_from_folder(folder, 6, frames=["base"])[0], tmp_path / "framed.npz")
    runs = []
    for model, frame in (("plain", ""), ("framed", ", frame: base")):
        finish_run(start_run(load_task(phi1_task(tmp_path, tmp_path / f"{model}.npz", frame)), tmp_path / model))
        runs.append([json.loads(line) for line in (tmp_path / model / "trials.jsonl").read_text().splitlines()])
    plain, framed = runs
    assert [trial["robustness"] for trial in plain] == [trial["robustness"] for trial in framed]
    assert [list(trial["parameters"].values()) for trial in plain] == [list(trial["parameters"].values()) for trial in framed]
    assert list(framed[0]["parameters"])[0] == "mean[2].base.x"


def placed_task(tmp_path: Path, extra: str = PLACEMENTS, means: str = "{components: [5, 6], together: true, frame: holder, coordinates: [x, y]}") -> Path:
    path = tmp_path / "placed.yaml"
    path.write_text(
        f"spec: {ROOT / 'specs' / 'phi3_strict_objects.stl'}\nbehaviour: {BEHAVIOUR}\nbackend: kinematic\nduration: 48\nrate: 20\n"
        f"parameters:\n  insert:\n    means: {means}\n"
        "optimizer: {initial: 2, trials: 3, seed: 1}\n" + extra
    )
    return path


@pytest.mark.slow
def test_several_placements_score_the_worst_and_record_each(tmp_path):
    task = load_task(placed_task(tmp_path))
    assert len(task.placements) == 2 and task.placements[1]["holder"].yaw == -0.3
    prepared = start_run(task, tmp_path / "run")
    objective = prepared.objective
    assert len(objective.placed) == 2 and objective.placed[1].scene.frame_poses["shaft"].position == (0.48, -0.28, 0.08)
    references = [placed.reference() for placed in objective.placed]
    assert np.abs(references[0].positions[-1] - references[1].positions[-1]).max() > 0.05  # the skill follows the holder
    finish_run(prepared)
    trials = [json.loads(line) for line in (tmp_path / "run" / "trials.jsonl").read_text().splitlines()]
    parts = objective.parts
    for trial in trials:
        names, values = list(trial["components"]), np.array(list(trial["components"].values()))
        assert [name.split(" (")[0] for name in names] == ["placement 1"] * 2 + ["placement 2"] * 2
        assert [name.split(": ", 1)[1] for name in names] == list(parts.names) * 2
        assert trial["robustness"] == pytest.approx(min(parts.compose(values[:2]), parts.compose(values[2:])))
    assert "insert.mean[5+6].holder.x" in trials[0]["parameters"]
    recorded = (tmp_path / "run" / "task.yaml").read_text()
    assert "placements:" in recorded and "frame: holder" in recorded
    from typer.testing import CliRunner

    from stl_lfd.cli import app

    report = CliRunner().invoke(app, ["report", str(tmp_path / "run"), "--out", str(tmp_path / "report")])
    assert report.exit_code == 0, report.stderr
    assert (tmp_path / "report" / "components.png").is_file()
    assert not (tmp_path / "report" / "transitions.png").exists()  # only the insert's means move
    assert "transitions.png</b>: the transitions were not optimised" in (tmp_path / "report" / "index.html").read_text()


@pytest.mark.parametrize(
    ("extra", "means", "message"),
    [
        ("place: {cup: [0.5, 0.2]}\n", None, "'place' names 'cup', which is not a frame of the scene pick_insert"),
        ("place: {holder: [0.9, 0.2]}\n", None, r"'place': holder at \(0.9, 0.2\) is outside the area"),
        ("place: {holder: [0.5]}\n", None, r"'place.holder' must be \[x, y\]"),
        ("place: {holder: [0.5, 0.2]}\n" + PLACEMENTS, None, r"give 'place' \(one placement\) or 'placements' \(several\), not both"),
        ("", "{components: [6], coordinates: [x]}", r"the model has frames \(base, shaft, holder\): say in which one the mean moves \('frame:'\)"),
        ("", "{components: [6], frame: cup}", r"the model has no frame cup \(its frames: base, shaft, holder\)"),
    ],
)
@pytest.mark.slow
def test_bad_placements_and_frames_name_the_file_and_key(tmp_path, extra, means, message, behaviour_models):
    from stl_lfd.optim.inputs import resolve
    from stl_lfd.optim.objective import objective_for

    path = placed_task(tmp_path, extra, means) if means else placed_task(tmp_path, extra)
    with pytest.raises(ConfigError) as error:
        objective_for(resolve(load_task(path)), behaviour_models, execute=False)
    assert str(path) in str(error.value) and __import__("re").search(message, str(error.value)), str(error.value)


@pytest.mark.slow
def test_optimize_from_python_takes_placements():
    from stl_lfd import MeanParameters, Optimizer, Parameters, Pose, optimize
    from stl_lfd.skill import behaviour_models, load_behaviour

    behaviour = load_behaviour(BEHAVIOUR)
    models = behaviour_models(behaviour)
    placements = [{"holder": Pose((0.52, 0.24, 0.04), 0.3)}, {"holder": Pose((0.6, 0.16, 0.04), -0.3)}]
    result = optimize(
        models,
        ROOT / "specs" / "phi3_strict_objects.stl",
        {"insert": Parameters(means=MeanParameters(components=(6,), coordinates=("x",), frame="holder"))},
        Optimizer(initial=2, trials=2, seed=0),
        duration=48,
        rate=20,
        scene="pick_insert",
        backend="kinematic",
        behaviour=BEHAVIOUR,
        placements=placements,
    )
    assert len(result.history) == 2 and len(result.history[0].components) == 4  # two placements of two parts
    with pytest.raises(ConfigError, match="outside the area"):
        optimize(models, ROOT / "specs" / "phi3_strict_objects.stl", {"insert": Parameters(means=MeanParameters(components=(6,), frame="holder"))},
                 duration=48, rate=20, scene="pick_insert", backend="kinematic", behaviour=BEHAVIOUR, placements=[{"holder": Pose((0.9, 0.2, 0.04))}])  # fmt: skip


def test_executions_outside_stlopt_take_one_placement(tmp_path):
    from stl_lfd.optim.inputs import resolve
    from stl_lfd.optim.runs.asktell import ask_new
    from stl_lfd.optim.runs.resume import inputs_record
    from stl_lfd.optim.task import Overrides

    task = load_task(placed_task(tmp_path))
    with pytest.raises(ConfigError, match="takes one placement"):
        ask_new(resolve(task), tmp_path / "run", inputs_record(task, Overrides(), resolve(task)))
    with pytest.raises(ConfigError, match="several placements need a simulated backend"):  # refused with the task, before any learning
        task.with_overrides(backend="command", command=__import__("stl_lfd").Command.parse("true"))
    assert not (tmp_path / "run").exists()


def test_grouped_parts_compose_per_placement_then_take_the_worst():
    import torch

    from stl_lfd.optim.methods.composition import compose
    from stl_lfd.stl import Semantics, split_spec
    from stl_lfd.stl import load_spec as read

    parts = split_spec(read(ROOT / "specs" / "phi3_strict_objects.stl"), "new")
    values = np.array([[0.02, 0.5, -0.01, 0.3, 0.04, 0.6]])  # three placements of two parts
    expected = min(parts.compose(values[0, i : i + 2]) for i in (0, 2, 4))
    assert float(compose(torch.as_tensor(values), Semantics("new"), groups=3)[0]) == pytest.approx(expected)
