"""The physical outcome signals (`NAME_speed`, `NAME_held`, `NAME_depth`, `NAME_offset`): the
geometry they rest on, and what the kinematic backend records for a pick and insert."""

import math

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.sim import Reference, execute, load_scene
from stl_lfd.sim.shapes import lowest_heights

UPRIGHT = np.array([[0.0, 0.0, 0.0, 1.0]])
LYING = rotations.from_euler(math.pi / 2, 0.0, 0.0)[None]


@pytest.mark.parametrize(
    "shape, size, orientation, lowest",
    [
        ("cylinder", (0.01, 0.12), UPRIGHT, 0.5 - 0.06),
        ("cylinder", (0.01, 0.12), LYING, 0.5 - 0.01),
        ("cylinder", (0.01, 0.12), rotations.from_euler(math.radians(30), 0.0, 0.0)[None], 0.5 - 0.06 * math.cos(math.radians(30)) - 0.01 * 0.5),
        ("box", (0.01, 0.02, 0.03), UPRIGHT, 0.5 - 0.03),
        ("box", (0.01, 0.02, 0.03), LYING, 0.5 - 0.02),
        ("sphere", (0.02,), LYING, 0.5 - 0.02),
    ],
)
def test_the_lowest_point_of_a_turned_shape(shape, size, orientation, lowest):
    assert lowest_heights(shape, size, np.array([[0.1, 0.2, 0.5]]), orientation)[0] == pytest.approx(lowest)


def carry_into_hole(scene, grasp, hole_top):
    """Down to the shaft, grasp at 2 s, carry it to `hole_top`, release at 8 s, rise."""
    times = np.arange(0.0, 10.0, 0.01)
    waypoints = np.array([grasp + [0, 0, 0.1], grasp, grasp, grasp + [0, 0, 0.15], hole_top + [0, 0, 0.1], hole_top, hole_top, hole_top + [0, 0, 0.1]])
    knots = np.array([0.0, 1.5, 2.5, 3.5, 5.0, 7.0, 8.2, 9.5])
    positions = np.column_stack([np.interp(times, knots, waypoints[:, axis]) for axis in range(3)])
    gripper = np.where((times >= 2.0) & (times < 8.0), 0.0, 0.08)
    return Reference(times, positions, gripper, ((2.0, "grasp"), (8.0, "release")))


def test_the_kinematic_backend_records_the_shaft_held_moving_and_in_the_hole():
    scene = load_scene("pick_insert")
    grasp, hole = np.array([0.45, -0.25, 0.11]), np.array([0.553, 0.20, 0.11])  # 3 mm off the hole's axis
    signals = execute(carry_into_hole(scene, grasp, hole), scene, "kinematic", rate=100.0).signals
    columns, times = signals.columns, signals.times
    held = columns["shaft_held"]
    assert np.all(held[(times >= 2.0) & (times < 8.0)] == 1.0) and np.all(held[(times < 1.99) | (times >= 8.01)] == 0.0)
    assert columns["shaft_speed"][times < 2.0].max() < 1e-9  # standing still before the grasp
    assert columns["shaft_speed"][(times > 3.7) & (times < 4.8)].max() > 0.1  # carried
    # the grasp point is 3 cm above the shaft's centre; its bottom 6 cm below the centre
    assert columns["shaft_depth"][0] == pytest.approx(0.06 - 0.02)  # standing on the table, as deep as the rim is high
    assert columns["shaft_depth"][-1] == pytest.approx(0.06 - (0.11 - 0.03 - 0.06))
    assert columns["shaft_offset"][-1] == pytest.approx(0.003, abs=1e-6)
    assert columns["shaft_offset"][0] == pytest.approx(math.hypot(0.1, 0.45))


ONTO_SCENE = """description: a box to put on a turned shelf
objects:
  - {name: table, shape: box, size: [0.25, 0.45, 0.01], position: [0.5, 0.0, 0.01]}
  - {name: box, shape: box, size: [0.02, 0.02, 0.03], position: [0.45, -0.22, 0.05], mass: 0.1}
  - {name: shelf, shape: box, size: [0.08, 0.10, 0.05], position: [0.55, 0.20, 0.07], orientation: [0, 0, 0.5]}
frames:
  box: {position: [0.45, -0.22, 0.05], objects: [box], onto: shelf}
  shelf: {position: [0.55, 0.20, 0.12], objects: [shelf]}
"""


def test_an_object_put_onto_a_target_records_its_height_and_offset_in_the_targets_axes(tmp_path):
    (tmp_path / "onto.yaml").write_text(ONTO_SCENE)
    scene = load_scene(str(tmp_path / "onto.yaml"))
    grasp = np.array([0.45, -0.22, 0.06])  # 1 cm above the box's centre
    along = np.array([np.cos(0.5), np.sin(0.5), 0.0])  # the shelf's x axis, turned 0.5 rad
    put_down = np.array([0.55, 0.20, 0.12 + 0.03 + 0.002 + 0.01]) + 0.015 * along  # 2 mm above the top, 15 mm along x
    columns = execute(carry_into_hole(scene, grasp, put_down), scene, "kinematic", rate=100.0).signals.columns
    assert columns["box_height"][0] == pytest.approx(0.02 - 0.12)  # on the table, 10 cm below the shelf's top
    assert columns["box_height"][-1] == pytest.approx(0.002, abs=1e-9)
    assert columns["box_dx"][-1] == pytest.approx(0.015, abs=1e-9) and columns["box_dy"][-1] == pytest.approx(0.0, abs=1e-9)
    assert columns["box_offset"][-1] == pytest.approx(0.015, abs=1e-9)


def test_onto_must_name_another_frame_and_start_with_a_movable_object(tmp_path):
    from stl_lfd.errors import ConfigError

    for bad, message in (
        (ONTO_SCENE.replace("onto: shelf", "onto: nowhere"), "'frames.box.onto' must name another frame"),
        (ONTO_SCENE.replace("[shelf]}", "[shelf], onto: box}"), "'frames.shelf.onto': the frame's first object, shelf, must be movable"),
        (ONTO_SCENE.replace("onto: shelf", "onto: shelf, into: shelf"), "either into a hole or onto a target"),
    ):
        (tmp_path / "bad.yaml").write_text(bad)
        with pytest.raises(ConfigError, match=message):
            load_scene(str(tmp_path / "bad.yaml"))


INSIDE_SCENE = """description: a box to put in a turned tray
objects:
  - {name: table, shape: box, size: [0.25, 0.45, 0.01], position: [0.5, 0.0, 0.01]}
  - {name: box, shape: box, size: [0.02, 0.02, 0.03], position: [0.45, -0.22, 0.05], mass: 0.1}
  - {name: tray, shape: box, size: [0.08, 0.10, 0.005], position: [0.55, 0.20, 0.025], orientation: [0, 0, 0.5]}
frames:
  box: {position: [0.45, -0.22, 0.05], objects: [box], inside: tray}
  tray: {position: [0.55, 0.20, 0.03], objects: [tray], interior: {lower: [-0.07, -0.09, 0.0], upper: [0.07, 0.09, 0.05]}}
"""


def test_an_object_put_inside_a_container_records_how_far_inside_it_is(tmp_path):
    (tmp_path / "inside.yaml").write_text(INSIDE_SCENE)
    scene = load_scene(str(tmp_path / "inside.yaml"))
    grasp = np.array([0.45, -0.22, 0.06])  # 1 cm above the box's centre
    along = np.array([np.cos(0.5), np.sin(0.5), 0.0])  # the tray's x axis, turned 0.5 rad
    # set down 1 mm above the tray's floor, 4 cm along its x axis: the box (2 cm half width) is then
    # 1 cm from the wall at x = 0.07, and its top (6 cm tall) 1.1 cm above the interior's top
    put_down = np.array([0.55, 0.20, 0.03 + 0.001 + 0.03 + 0.01]) + 0.04 * along
    columns = execute(carry_into_hole(scene, grasp, put_down), scene, "kinematic", rate=100.0).signals.columns
    assert scene.recorded_signals[-1] == "box_inside"
    assert columns["box_inside"][-1] == pytest.approx(0.05 - 0.061, abs=1e-9)  # it sticks out of the top by 11 mm
    assert columns["box_inside"][0] < -0.2  # on the table, far from the tray


def test_extents_along_axes_are_exact_at_any_tilt():
    from stl_lfd.sim.shapes import extents_along

    tilted = rotations.from_euler(0.3, -0.2, 1.1)[None]
    axes = rotations.to_matrix(tilted).swapaxes(-1, -2)  # the object's own axes: its half extents
    assert extents_along("box", (0.01, 0.02, 0.03), tilted, axes)[0] == pytest.approx([0.01, 0.02, 0.03])
    assert extents_along("cylinder", (0.01, 0.1), tilted, axes)[0] == pytest.approx([0.01, 0.01, 0.05])
    diagonal = (axes[:, 0] + axes[:, 2])[:, None] / np.sqrt(2)
    assert extents_along("cylinder", (0.01, 0.1), tilted, diagonal)[0, 0] == pytest.approx((0.05 + 0.01) / np.sqrt(2))
    assert extents_along("sphere", (0.02,), tilted, axes)[0] == pytest.approx([0.02] * 3)


def test_inside_must_name_a_frame_with_an_interior(tmp_path):
    from stl_lfd.errors import ConfigError

    for bad, message in (
        (INSIDE_SCENE.replace("inside: tray", "inside: table"), "'frames.box.inside' must name another frame with an 'interior'"),
        (INSIDE_SCENE.replace("upper: [0.07, 0.09, 0.05]", "upper: [0.07, -0.1, 0.05]"), "'frames.tray.interior' must have lower < upper"),
    ):
        (tmp_path / "bad.yaml").write_text(bad)
        with pytest.raises(ConfigError, match=message):
            load_scene(str(tmp_path / "bad.yaml"))
