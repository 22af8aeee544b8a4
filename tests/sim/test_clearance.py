"""Clearances (`NAME_clearance`): the signed distance from the hand, its fingers and what they
hold to an object, exact for boxes, cylinders and spheres at any pose."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.errors import ConfigError
from stl_lfd.poses import Pose
from stl_lfd.sim import load_scene
from stl_lfd.sim.clearance import FINGER_CENTRE_Z, FINGER_HALF, clearance_columns
from stl_lfd.sim.scene import Scene, SceneFrame, SceneObject
from stl_lfd.sim.steps import Steps

FINGERTIP = FINGER_CENTRE_Z + FINGER_HALF[2]  # m: how far the fingertips reach past the grasp target (7.2 mm)


def steps_at(positions, opening=0.08, orientation=rotations.DOWN, frames=((), (), ())):
    positions = np.asarray(positions, dtype=float)
    count = len(positions)
    frame_positions, frame_orientations, held = (np.asarray(values, dtype=float).reshape(count, -1, size) for values, size in zip(frames, (3, 4, 1)))
    orientations, openings = np.tile(orientation, (count, 1)), np.full(count, opening)
    return Steps(np.arange(count) * 0.01, positions, orientations, openings, np.zeros((count, 6)), frame_positions, frame_orientations, held[..., 0] > 0.5)


def scene_with(*objects, frames=()):
    return Scene("test", "a test scene", objects=tuple(objects), frames=tuple(frames))


def test_fingertips_above_a_box_are_their_height_above_its_top():
    table = SceneObject("table", "box", (0.2, 0.2, 0.01), (0.5, 0.0, 0.01), clearance=("hand",))
    heights = np.array([0.10, 0.05, 0.03])
    steps = steps_at([[0.5, 0.0, 0.02 + height] for height in heights])
    assert clearance_columns(steps, scene_with(table))["table_clearance"] == pytest.approx(heights - FINGERTIP, abs=1e-6)


def test_a_finger_beside_a_post_and_inside_it():
    post = SceneObject("post", "cylinder", (0.01, 0.08), (0.5, 0.1, 0.04), clearance=("hand",))  # its top 24 mm below the palm
    opening = 0.06
    # the left finger's outer face is at y = opening / 2 + 2 * FINGER_HALF[1] beside the grasp target
    outer = opening / 2 + 2 * FINGER_HALF[1]
    gaps = np.array([0.02, 0.005, -0.003])
    steps = steps_at([[0.5, 0.1 - 0.01 - outer - gap, 0.065] for gap in gaps], opening=opening)
    clearance = clearance_columns(steps, scene_with(post))["post_clearance"]
    assert clearance == pytest.approx(gaps, abs=1e-5)  # signed: negative inside (GJK on a cylinder: to 10 micrometres)


def test_a_tilted_box_is_measured_exactly():
    turn = (0.0, 0.0, np.pi / 4)
    block = SceneObject("block", "box", (0.02, 0.02, 0.02), (0.5, 0.0, 0.02), turn, clearance=("hand",))
    # straight above the block's top: the fingertips 3 cm above it, whatever its yaw
    steps = steps_at([[0.5, 0.0, 0.04 + 0.03 + FINGERTIP]], opening=0.0)
    assert clearance_columns(steps, scene_with(block))["block_clearance"][0] == pytest.approx(0.03, abs=1e-6)


def test_what_the_fingers_hold_counts_as_the_hand():
    wall = SceneObject("wall", "box", (0.01, 0.2, 0.1), (0.65, 0.0, 0.1), clearance=("hand",))  # its face at x = 0.64
    peg = SceneObject("peg", "cylinder", (0.01, 0.2), (0.5, 0.0, 0.1), mass=0.05)
    frame = SceneFrame("peg", Pose((0.5, 0.0, 0.1), 0.0), ("peg",))
    lying = rotations.from_euler(0.0, np.pi / 2, 0.0)  # along x: its far end at x = 0.6
    frames = ([[[0.5, 0.0, 0.1]]] * 2, [[lying]] * 2, [[[0.0]], [[1.0]]])  # let go, then held
    steps = steps_at([[0.5, 0.0, 0.1]] * 2, opening=0.02, frames=frames)
    clearance = clearance_columns(steps, scene_with(wall, peg, frames=[frame]))["wall_clearance"]
    assert clearance == pytest.approx([0.64 - (0.5 + 0.0316), 0.64 - 0.6], abs=1e-6)  # the palm's side, then the peg's end
    between = replace(peg, clearance=("wall",))
    columns = clearance_columns(steps, scene_with(wall, between, frames=[frame]))
    assert columns["peg_clearance_wall"] == pytest.approx([0.04, 0.04], abs=1e-6)  # the objects' own distance, held or not


def test_a_scene_file_declares_clearances(tmp_path: Path):
    text = (
        "description: a post\n"
        "objects:\n"
        "  - {name: post, shape: cylinder, size: [0.01, 0.2], position: [0.5, 0.1, 0.1], clearance: true}\n"
        "  - {name: box, shape: box, size: [0.02, 0.02, 0.02], position: [0.4, 0.0, 0.02], mass: 0.1, clearance: %s}\n"
    )
    path = tmp_path / "scene.yaml"
    path.write_text(text % "false")
    scene = load_scene(path)
    assert scene.recorded_signals[-1] == "post_clearance"
    path.write_text(text % "maybe")
    with pytest.raises(ConfigError, match=r"'objects\[1\].clearance' must be true, false or a list"):
        load_scene(path)
    path.write_text(text % "[post, pillar]")
    with pytest.raises(ConfigError, match=r"'objects\[1\].clearance' names 'pillar': it must be hand or another object"):
        load_scene(path)
    path.write_text(text % "true")
    with pytest.raises(ConfigError, match=r"box is movable.*list it first in a frame"):
        load_scene(path)


POST_SCENE = """description: a post beside the hand's way
objects:
  - {name: post, shape: cylinder, size: [0.02, 0.08], position: [0.5, 0.1, 0.04], clearance: true}
"""


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["kinematic", "pybullet", "mujoco"])
def test_a_finger_pushed_against_a_post_reads_no_clearance(engine, tmp_path: Path):
    from stl_lfd.sim import Reference, execute

    path = tmp_path / "post.yaml"
    path.write_text(POST_SCENE)
    scene = load_scene(path)
    outer = 0.04 + 2 * FINGER_HALF[1]  # the open fingers' outer face beside the grasp target
    start, touch = 0.1 - 0.02 - outer - 0.015, 0.1 - 0.02 - outer  # the palm passes 19 mm over the post's top
    times = np.arange(0, 3.0, 1 / 240)
    phase = np.clip((times - 0.5) / 2.0, 0.0, 1.0)
    y = start + (touch + 0.01 - start) * (10 * phase**3 - 15 * phase**4 + 6 * phase**5)  # 1 cm into the post
    reference = Reference(times, np.column_stack([np.full_like(times, 0.5), y, np.full_like(times, 0.06)]))
    signals = execute(reference, scene, engine, rate=100).signals
    clearance, force = np.asarray(signals.columns["post_clearance"]), np.asarray(signals.columns["force"])
    assert clearance[0] == pytest.approx(0.015, abs=0.001)  # from the recorded hand pose, whatever the engine
    if engine == "kinematic":
        assert clearance[-1] == pytest.approx(-0.01, abs=1e-4)  # it records the reference: the finger inside the post
    else:
        touching = force > 1.0
        assert touching[-1] and clearance[touching].max() < 0.001  # pushing on the post: no clearance left
