"""`stlopt report` on a small kinematic run: every figure written, valid, not blank, linked."""

import dataclasses
import html
import re

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from stl_lfd.cli import app
from stl_lfd.optim import finish_run, load_task, start_run
from stl_lfd.report import figures
from stl_lfd.report.figures import FigureSpec, figure_named
from stl_lfd.report.run_data import load_run
from stl_lfd.signals import read_signal_csv, write_signal_csv
from tests.conftest import ROOT

runner = CliRunner()
FIGURES = ["trajectories", "region_distances", "robustness", "components", "gp_slices", "transitions", "durations"]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, learned_model_file):
    folder = tmp_path_factory.mktemp("report")
    task = folder / "task.yaml"
    task.write_text(
        f"name: small\nspec: {ROOT / 'specs' / 'phi2.stl'}\nmodel: {learned_model_file}\nbackend: kinematic\nduration: 22\nrate: 20\n"
        "parameters:\n  means: {components: [3]}\n  durations: {components: all}\n  transitions: band\n"
        "optimizer: {initial: 3, trials: 6, seed: 0}\n"
    )
    finish_run(start_run(load_task(task), folder / "run"))
    return folder / "run"


def assert_picture(path):
    with Image.open(path) as image:
        assert image.format == "PNG"
        pixels = np.asarray(image.convert("L"), dtype=float)
    assert pixels.shape[0] > 200 and pixels.shape[1] > 300
    assert pixels.std() > 5  # not a blank canvas


def page_text(path):
    """What a reader of the page sees: its text without tags."""
    return html.unescape(re.sub(r"<[^>]+>", "", path.read_text()))


@pytest.mark.slow
def test_report_writes_every_figure_and_an_index(run_dir, tmp_path):
    out = tmp_path / "report"
    result = runner.invoke(app, ["report", str(run_dir), "--out", str(out)])
    assert result.exit_code == 0, result.stderr
    listed = result.stdout.split()
    assert listed[-1] == str(out / "index.html")
    for name in FIGURES:
        assert str(out / f"{name}.png") in listed
        assert_picture(out / f"{name}.png")
    for name in FIGURES:
        assert f'src="{name}.png"' in (out / "index.html").read_text()
    page = page_text(out / "index.html")
    summary = load_run(run_dir).summary
    assert f"the best trial ({summary.best_trial} of 6) scores {summary.best_robustness:+.5f} (new robustness (nu = 1))" in page
    assert f"the unoptimised skill scored {summary.initial_robustness:+.5f}" in page
    assert "phi2 := " in page  # the spec as written
    assert "6 trials: 3 chosen on their plans, then plan" in page  # as stlopt optimize names the phases
    assert "the means of state 3 (x, y, z), within ±2 standard deviations" in page and "the transition band" in page
    assert f"stlopt replay {run_dir.resolve()} --trial {summary.best_trial}" in page
    assert "Black arrows" not in page  # the hand points down throughout: no approach axes drawn or named
    assert not (out / "forces.png").exists()  # the kinematic backend touches nothing
    assert not (out / "tilt.png").exists()  # a skill without orientation points the hand down throughout


@pytest.mark.slow
def test_forces_and_comparison_when_the_data_is_there(run_dir, tmp_path):
    touched = tmp_path / "touched"
    import shutil

    shutil.copytree(run_dir, touched)
    signals = touched / "signals" / "trial-0002.csv"
    table = read_signal_csv(signals)
    table.columns["force"] = np.linspace(0.0, 3.0, table.samples)
    write_signal_csv(table, signals)
    initial = read_signal_csv(touched / "signals" / "initial.csv")  # a wrist sensor's reading of the unoptimised skill
    ramp = np.linspace(0.0, 3.0, initial.samples)
    initial.columns |= {"force": ramp, "fx": 0 * ramp, "fy": 0 * ramp, "fz": ramp, "tx": 0.01 * ramp, "ty": 0 * ramp, "tz": 0 * ramp}
    write_signal_csv(initial, touched / "signals" / "initial.csv")
    out = tmp_path / "report"
    result = runner.invoke(app, ["report", str(touched), "--out", str(out), "--compare", str(run_dir), "--gp-parameter", "duration[4]"])
    assert result.exit_code == 0, result.stderr
    assert_picture(out / "forces.png")
    assert_picture(out / "wrench.png")
    assert_picture(out / "compare.png")
    assert 'src="forces.png"' in (out / "index.html").read_text()


@pytest.mark.slow
def test_report_errors_are_one_line(run_dir, tmp_path):
    missing = runner.invoke(app, ["report", str(tmp_path / "nothing")])
    assert missing.exit_code == 9 and "no such run directory" in missing.stderr
    bad = runner.invoke(app, ["report", str(run_dir), "--out", str(tmp_path / "r"), "--gp-parameter", "mean[9].q"])
    assert bad.exit_code == 5 and "is not a parameter of the run" in bad.stderr


@pytest.mark.slow
def test_report_of_a_behaviour_run_draws_each_skill(tmp_path):
    from stl_lfd.optim import load_task

    task = load_task(ROOT / "configs" / "phi3_strict.yaml").with_overrides(backend="kinematic", trials=3, initial=2)
    finish_run(start_run(task, tmp_path / "run"))
    result = runner.invoke(app, ["report", str(tmp_path / "run"), "--out", str(tmp_path / "report")])
    assert result.exit_code == 0, result.stderr
    for name in FIGURES:
        assert_picture(tmp_path / "report" / f"{name}.png")
    page = page_text(tmp_path / "report" / "index.html")
    assert "pick.duration[1]" in page and "insert.mean[5+6].holder.x" in page
    assert "pick: the duration means of" in page and "insert: the means of" in page


@pytest.mark.slow
def test_captions_follow_the_semantics_and_unused_figures_say_why(tmp_path, learned_model_file):
    task = tmp_path / "task.yaml"
    task.write_text(
        f"name: plain\nspec: {ROOT / 'specs' / 'phi1.stl'}\nmodel: {learned_model_file}\nbackend: kinematic\nduration: 22\nrate: 20\n"
        "semantics: classic\nparameters:\n  durations: {components: [2, 4]}\noptimizer: {method: random, initial: 2, trials: 3, seed: 1}\n"
    )
    finish_run(start_run(load_task(task), tmp_path / "run"))
    result = runner.invoke(app, ["report", str(tmp_path / "run")])
    assert result.exit_code == 0, result.stderr
    report = tmp_path / "run" / "report"
    assert not (report / "transitions.png").exists()
    page = page_text(report / "index.html")
    assert "transitions.png: the transitions were not optimised, so the graph is the same before and after" in page
    assert "3 trials: 2 Sobol, then random" in page and "classic robustness" in page
    assert "The spec's value is their minimum, so the lowest part (circled) is the spec's value" in page
    run = load_run(tmp_path / "run")
    assert all(trial.robustness == min(trial.components.values()) for trial in run.trials)  # what the caption says
    under_new = dataclasses.replace(run, task=dataclasses.replace(run.task, semantics="new"))
    assert "the new robustness's conjunction (nu = 1)" in figure_named("components").caption(under_new)


@pytest.mark.slow
def test_a_run_that_turns_the_hand_draws_its_tilt_and_approach_axis(tmp_path):
    folder = tmp_path / "turn"
    task = load_task(ROOT / "configs" / "turn.yaml").with_overrides(initial=2, trials=3)
    finish_run(start_run(task, folder))
    result = runner.invoke(app, ["report", str(folder)])
    assert result.exit_code == 0, result.stderr
    assert_picture(folder / "report" / "tilt.png")
    assert 'src="tilt.png"' in (folder / "report" / "index.html").read_text()
    assert "Black arrows: where the best trial's hand points" in page_text(folder / "report" / "index.html")


def test_only_the_regions_the_spec_uses_are_drawn(tmp_path):
    from stl_lfd.report.run_data import used_regions
    from stl_lfd.stl import load_spec

    (tmp_path / "regions.stl").write_text((ROOT / "specs" / "regions.stl").read_text())
    (tmp_path / "mine.stl").write_text('include "regions.stl"\nNEAR := L1\nmine := F NEAR & G[0, 5] !L3\n')
    assert list(used_regions(load_spec(tmp_path / "mine.stl"))) == ["L1", "L3"]


@pytest.mark.slow
def test_a_contact_run_draws_its_objects_and_the_specs_thresholds_on_their_signals(tmp_path):
    task = load_task(ROOT / "configs" / "phi3_inserted.yaml").with_overrides(backend="kinematic", method="random", initial=2, trials=3)
    finish_run(start_run(task, tmp_path / "run"))
    result = runner.invoke(app, ["report", str(tmp_path / "run")])
    assert result.exit_code == 0, result.stderr
    report = tmp_path / "run" / "report"
    assert_picture(report / "objects.png")
    page = page_text(report / "index.html")
    assert "Grey: the objects the task is about" in page and "dashed green, the spec's thresholds" in page
    assert "shaft_depth, how deep shaft's lowest point is below holder's rim (m)" in page  # the scene's own names
    run = load_run(tmp_path / "run")
    from stl_lfd.report import objects

    assert objects.constrained_object_signals(run) == ["shaft_held", "shaft_speed", "shaft_depth", "shaft_offset", "shaft_tilt"]
    # an object's offset from its target written as an expression is drawn too; the hand's is not
    from stl_lfd.stl import parse
    from stl_lfd.stl.thresholds import expression_thresholds

    spec = parse("mine := F G abs(shaft_x - holder_x) < 0.004 & F abs(x - shaft_x) < 0.01\n")
    offsets = dataclasses.replace(run, expression_thresholds=expression_thresholds(spec))
    assert objects.constrained_object_expressions(offsets) == ["abs(shaft_x - holder_x)"]
    assert len(objects.object_signals(offsets, lambda axes, run, curves: None).axes) == 6
    assert {item.name for item in objects.fixed_frame_objects(run)} == {"holder_left", "holder_right", "holder_front", "holder_back"}


def test_an_objects_outline_is_its_turned_box_seen_from_a_side():
    from stl_lfd.report.objects import corners, outline
    from stl_lfd.sim.scene import SceneObject

    wall = SceneObject("wall", "box", (0.01, 0.03, 0.02), (0.5, 0.2, 0.04), orientation=(0.0, 0.0, np.pi / 2))
    top = outline(corners(wall)[:, :2])
    assert (
        len(top) == 4
        and np.allclose(np.sort(np.unique(np.round(top[:, 0], 6))), [0.47, 0.53])
        and np.allclose(np.sort(np.unique(np.round(top[:, 1], 6))), [0.19, 0.21])
    )


@pytest.mark.slow
def test_a_missing_signal_file_is_named_not_silently_dropped(run_dir, tmp_path):
    import shutil

    damaged = tmp_path / "damaged"
    shutil.copytree(run_dir, damaged)
    (damaged / "signals" / "trial-0002.csv").unlink()
    result = runner.invoke(app, ["report", str(damaged), "--out", str(tmp_path / "report")])
    assert result.exit_code == 0, result.stderr
    assert "warning: " in result.stderr and "the recorded signals signals/trial-0002.csv are missing; the figures leave their trials out" in result.stderr
    assert "Missing from the run directory, so left out of every figure: signals/trial-0002.csv." in page_text(tmp_path / "report" / "index.html")


class SpeedPerTrial(FigureSpec):
    """A figure a contributor might add: the hand's top speed per trial."""

    name = "top_speed"
    left_out = "no trial recorded positions"

    def applies(self, run, options):
        return bool(run.signals)

    def draw(self, run, options):
        from matplotlib.figure import Figure

        figure = Figure(figsize=(6, 3))
        axes = figure.subplots()
        numbers = sorted(run.signals)
        speeds = [np.max(np.linalg.norm(np.diff(np.column_stack([run.signals[n].columns[a] for a in "xyz"]), axis=0), axis=1)) for n in numbers]
        axes.bar([str(number) for number in numbers], speeds)
        return figure

    def caption(self, run):
        return f"The hand's top speed in each of the {len(run.signals)} recorded trials."


@pytest.mark.slow
def test_a_new_figure_is_one_spec_class_and_one_registry_line(run_dir, tmp_path, monkeypatch):
    monkeypatch.setattr(figures, "FIGURES", (*figures.FIGURES, SpeedPerTrial()))  # the registry line
    out = tmp_path / "report"
    result = runner.invoke(app, ["report", str(run_dir), "--out", str(out)])
    assert result.exit_code == 0, result.stderr
    assert str(out / "top_speed.png") in result.stdout.split()
    assert_picture(out / "top_speed.png")
    assert "top_speed.png: The hand's top speed in each of the 7 recorded trials." in page_text(out / "index.html")


def test_a_learned_skill_and_a_sweep_are_drawn_by_registered_figures(tmp_path):
    from stl_lfd.report.figures import SkillDrawing, save_figure

    demo = np.column_stack([np.linspace(0, 1, 50), np.linspace(0, 0.5, 50)])
    drawing = SkillDrawing([demo, demo + 0.01], demo[[0, 25, 49]], np.tile(np.eye(2) * 1e-3, (3, 1, 1)), demo, 0.1, ["x", "y"])
    skill = figure_named("skill")
    save_figure(skill.draw(drawing), tmp_path / "skill.png")
    assert (tmp_path / "skill.png").stat().st_size > 1000
    assert "2 demonstrations" in skill.caption(drawing) and "3 states" in skill.caption(drawing)
    assert figure_named("sweep").name == "sweep"


def test_an_object_signal_is_described_with_the_scenes_own_names(tmp_path):
    from stl_lfd.report.objects import signal_in_words
    from stl_lfd.sim import load_scene
    from tests.sim.test_outcome import ONTO_SCENE

    (tmp_path / "onto.yaml").write_text(ONTO_SCENE)
    scene = load_scene(str(tmp_path / "onto.yaml"))
    assert signal_in_words("box_height", scene) == "box_height, how high box's lowest point is above shelf's origin (m)"
    assert signal_in_words("box_offset", scene) == "box_offset, box's distance from shelf (m)"
    assert signal_in_words("force", scene) == "force"


def test_the_objects_drawn_are_the_frames_fixed_objects_and_the_obstacles():
    from stl_lfd.poses import Pose
    from stl_lfd.report.objects import fixed_objects
    from stl_lfd.sim.scene import Scene, SceneFrame, SceneObject

    table = SceneObject("table", "box", (0.25, 0.45, 0.01), (0.5, 0.0, 0.01))
    post = SceneObject("post", "cylinder", (0.01, 0.1), (0.5, 0.1, 0.05), clearance=("hand",))
    holder = SceneObject("holder", "box", (0.02, 0.02, 0.02), (0.6, 0.1, 0.02))
    scene = Scene("s", "a scene", objects=(table, post, holder), frames=(SceneFrame("holder", Pose((0.6, 0.1, 0.04), 0.0), ("holder",)),))
    assert [item.name for item in fixed_objects(scene, 1)] == ["post", "holder"]
    assert fixed_objects(scene, 2) == []
