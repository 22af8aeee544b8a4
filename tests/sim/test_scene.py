from pathlib import Path

import numpy as np
import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.sim import builtin_scenes, load_scene
from stl_lfd.sim.scene_file import placement_from_options


def test_free_space_is_built_in():
    assert "free_space" in builtin_scenes()
    scene = load_scene("free_space")
    assert scene.name == "free_space" and scene.objects == () and scene.regions == ()
    control = scene.control
    assert 200 <= control.translational_stiffness <= 1000 and 10 <= control.rotational_stiffness <= 30  # as the real robot's example controllers
    assert control.torque_limits == (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0) and 0 < control.finger_force <= 70


def test_regions_need_all_three_coordinates():
    scene = load_scene("free_space").with_regions({"L1": {"x": (0.3, 0.4), "y": (0.0, 0.1), "z": (0.3, 0.4)}, "slab": {"x": (0.0, 1.0)}})
    assert [region.name for region in scene.regions] == ["L1"]
    assert scene.regions[0].lower == (0.3, 0.0, 0.3)


def test_unknown_scene_lists_the_built_in_ones():
    with pytest.raises(ConfigError, match="unknown scene 'kitchen'.*free_space"):
        load_scene("kitchen")


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return path


def test_a_user_scene_file_with_objects(tmp_path):
    path = write(
        tmp_path,
        "description: a block\nobjects:\n  - {name: block, shape: box, size: [0.02, 0.02, 0.02], position: [0.5, 0, 0.02], mass: 0.1}\n",
    )
    scene = load_scene(path)
    assert scene.name == "scene" and scene.objects[0].mass == 0.1


@pytest.mark.parametrize(
    "text, message",
    [
        ("description: d\ncontrl: {}\n", "unknown key 'contrl'"),
        ("description: d\ncamera: {zoom: 2}\n", "unknown key 'camera.zoom'"),
        (
            "description: d\ncontrol: {position_gain: 0.3}\n",
            r"'control.position_gain' belonged to the position-controlled arm; .* \(set translational_stiffness",
        ),
        ("description: d\ncontrol: {translational_stiffness: 1e9}\n", r"'control.translational_stiffness' must be at most 5000"),
        ("description: d\ncontrol: {rotational_stiffness: -1}\n", r"'control.rotational_stiffness' must be positive"),
        ("description: d\ncontrol: {finger_force: 500}\n", r"'control.finger_force' must be at most 140"),
        ("description: d\ncontrol: {nullspace_posture: ik}\n", r"'control.nullspace_posture' must be one of rest, current \(got 'ik'\)"),
        ("description: d\ncontrol: {torque_limits: [87, 87, 87, 87, 12, 12, 100]}\n", r"'control.torque_limits' must be positive and at most the Panda's"),
        ("description: d\nobjects:\n  - {name: a, shape: cone, size: [1], position: [0, 0, 0]}\n", r"'objects\[0\].shape' must be one of"),
        ("description: d\nobjects:\n  - {name: a, shape: box, size: [1, 1], position: [0, 0, 0]}\n", r"'objects\[0\].size' must be a list of 3"),
        ("gripper_opening: 0.08\n", "missing key 'description'"),
        ("description: [unclosed\n", r"scene.yaml:\d+:\d+: invalid YAML"),
    ],
)
def test_bad_scene_files_name_the_file_and_key(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=message) as error:
        load_scene(path)
    assert str(path) in str(error.value)


def test_placing_a_frame_moves_its_objects_rigidly():
    import numpy as np

    from stl_lfd.poses import Pose

    scene = load_scene("pick_insert")
    holder = scene.frame_poses["holder"]
    placed = scene.place({"holder": Pose((0.6, 0.1, 0.04), 0.5)})
    before = {item.name: item for item in scene.objects}
    for item in placed.objects:
        if item.name.startswith("holder_"):
            local = holder.from_base(np.array([before[item.name].position]))
            assert np.allclose(item.position, Pose((0.6, 0.1, 0.04), 0.5).to_base(local)[0])
            assert item.orientation[2] == pytest.approx(before[item.name].orientation[2] + 0.5)
        else:
            assert item == before[item.name]
    assert placed.frame_poses["holder"] == Pose((0.6, 0.1, 0.04), 0.5)
    assert placed.recorded_signals[-16:] == (
        "shaft_x", "shaft_y", "shaft_z", "holder_x", "holder_y", "holder_z", "shaft_tilt", "holder_tilt",
        "shaft_speed", "shaft_held", "shaft_depth", "shaft_offset", "shaft_qx", "shaft_qy", "shaft_qz", "shaft_qw",
    )  # fmt: skip


def test_placements_outside_the_table_or_of_unknown_frames_are_refused():
    from stl_lfd.spelling import spelled_as

    scene = load_scene("pick_insert")
    with pytest.raises(ConfigError, match=r"'place': holder at \(0.9, 0.2\) is outside the area it may be placed in \(x 0.3 to 0.7"):
        scene.place(placement_from_options(scene, ["holder=0.9,0.2"]))
    with pytest.raises(ConfigError, match=r"'place' cup=0.5,0.2: no frame 'cup' \(frames: shaft, holder\)"):
        placement_from_options(scene, ["cup=0.5,0.2"])
    restore = spelled_as({"place": "--place"})  # as the command line names the setting
    try:
        with pytest.raises(ConfigError, match=r"--place cup=0.5,0.2: no frame 'cup'"):
            placement_from_options(scene, ["cup=0.5,0.2"])
    finally:
        restore()
    with pytest.raises(ConfigError, match=r"'place' cup=0.5,0.2"):
        placement_from_options(scene, ["cup=0.5,0.2"])
    with pytest.raises(ConfigError, match="holder is placed twice"):
        placement_from_options(scene, ["holder=0.5,0.2", "holder=0.5,0.25"])
    placement = placement_from_options(scene, ["shaft=0.4,-0.3"])
    assert placement["shaft"].position == (0.4, -0.3, 0.08) and placement["shaft"].yaw == 0.0


def test_a_symmetric_frame_takes_the_equivalent_yaw_nearest_its_scene_yaw():
    import math
    from dataclasses import replace

    import numpy as np

    from stl_lfd.poses import Pose

    scene = load_scene("pick_reorient_insert")
    frames = {frame.name: frame for frame in scene.frames}
    assert (frames["shaft"].symmetry, frames["holder"].symmetry) == (2, 4)
    assert frames["shaft"].equivalent(Pose((0.5, -0.2, 0.056), math.radians(170))).yaw == pytest.approx(math.radians(-10))
    assert frames["holder"].equivalent(Pose((0.5, 0.2, 0.04), math.radians(-100))).yaw == pytest.approx(math.radians(-10))
    assert frames["holder"].equivalent(Pose((0.5, 0.2, 0.04), math.radians(44))).yaw == pytest.approx(math.radians(44))
    turned = scene.place({"shaft": Pose((0.5, -0.2, 0.056), math.radians(170)), "holder": Pose((0.5, 0.2, 0.04), math.radians(-100))})
    assert turned.frame_poses["shaft"].yaw == pytest.approx(math.radians(-10))
    assert turned.frame_poses["holder"].yaw == pytest.approx(math.radians(-10))
    # the objects stand where the placement asked, the half-turned rails swapped
    asymmetric = replace(scene, frames=tuple(replace(frame, symmetry=1) for frame in scene.frames))
    asked = asymmetric.place({"shaft": Pose((0.5, -0.2, 0.056), math.radians(170))})
    rails = {item.name: np.array(item.position) for item in turned.objects if item.name.startswith("rest_")}
    other = {item.name: np.array(item.position) for item in asked.objects if item.name.startswith("rest_")}
    assert np.allclose(rails["rest_left"], other["rest_right"]) and np.allclose(rails["rest_right"], other["rest_left"])
    assert not np.allclose(rails["rest_left"], other["rest_left"])
    # a scene without symmetry keeps every yaw
    plain = load_scene("pick_insert")
    assert plain.place({"holder": Pose((0.6, 0.1, 0.04), 3.0)}).frame_poses["holder"].yaw == 3.0


@pytest.mark.parametrize("value", ["0", "1.5", "true", "two"])
def test_a_frame_symmetry_must_be_a_positive_whole_number(tmp_path, value):
    path = write(
        tmp_path,
        "description: d\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02]}\n"
        f"frames:\n  cup: {{position: [0.5, 0, 0.02], objects: [a], symmetry: {value}}}\n",
    )
    with pytest.raises(ConfigError, match=r"'frames.cup.symmetry' must be a whole number") as error:
        load_scene(path)
    assert str(path) in str(error.value)


HOLE_SCENE = (
    "description: d\nobjects:\n"
    "  - {name: peg, shape: cylinder, size: [0.01, 0.1], position: [0.4, 0, 0.07], mass: 0.05}\n"
    "  - {name: block, shape: box, size: [0.02, 0.02, 0.02], position: [0.6, 0, 0.04]}\n"
    "frames:\n  peg: {position: [0.4, 0, 0.07], objects: [peg], %s}\n  cup: {position: [0.6, 0, 0.04], objects: [block], %s}\n"
)


def test_a_frame_that_goes_into_a_hole_records_its_depth_and_offset(tmp_path):
    scene = load_scene(write(tmp_path, HOLE_SCENE % ("into: cup", "rim: 0.02")))
    assert scene.frames[0].into == "cup" and scene.frames[1].rim == 0.02
    assert scene.recorded_signals[-8:] == (
        "peg_speed",
        "peg_held",
        "peg_depth",
        "peg_offset",
        "peg_qx",
        "peg_qy",
        "peg_qz",
        "peg_qw",
    )  # the fixed cup has no motion signals


@pytest.mark.parametrize(
    "peg, cup, message",
    [
        ("into: cup", "symmetry: 1", r"'frames.peg.into' must name another frame with a 'rim' \(a hole; got 'cup'; frames with one: none\)"),
        ("into: peg, rim: 0.01", "symmetry: 1", r"'frames.peg.into' must name another frame with a 'rim'"),
        ("rim: 0.01", "into: peg", r"'frames.cup.into': the frame's first object, block, must be movable"),
        ("into: [cup]", "rim: 0.02", r"'frames.peg.into' must name the frame whose hole the object goes into"),
        ("into: cup", "rim: high", r"'frames.cup.rim' must be a number"),
    ],
)
def test_bad_holes_name_the_file_and_the_frame(tmp_path, peg, cup, message):
    path = write(tmp_path, HOLE_SCENE % (peg, cup))
    with pytest.raises(ConfigError, match=message) as error:
        load_scene(path)
    assert str(path) in str(error.value)


def test_a_rim_within_its_walls_is_accepted_up_to_their_top_and_bottom(tmp_path):
    from stl_lfd.errors import ConfigError
    from stl_lfd.sim.scene_file import load_scene
    from tests.test_misuse import HOLE_SCENE

    for rim, accepted in ((0.02, True), (-0.02, True), (0.0, True), (0.021, False), (-0.021, False)):
        (tmp_path / "s.yaml").write_text(HOLE_SCENE.format(rim=rim))
        try:
            load_scene(str(tmp_path / "s.yaml"))
        except ConfigError:
            assert not accepted, rim
        else:
            assert accepted, rim


def test_a_region_is_drawn_as_its_edges_so_that_what_stands_inside_it_shows_in_videos():
    from stl_lfd.sim.pybullet_panda import PandaWorld
    from stl_lfd.sim.scene import Camera, Region, Scene, SceneObject

    edges = Region("L", (0.0, 0.0, 0.0), (0.2, 0.4, 0.6)).edges(0.01)
    assert len(edges) == 12 and sorted({tuple(np.round(2 * half, 3)) for _, half in edges}) == [(0.01, 0.01, 0.61), (0.01, 0.41, 0.01), (0.21, 0.01, 0.01)]
    box = SceneObject("box", "box", (0.03, 0.03, 0.03), (0.5, 0.2, 0.03), color=(1.0, 0.0, 0.0, 1.0))
    camera = Camera(target=(0.5, 0.2, 0.05), distance=0.6, yaw=60, pitch=-35, width=160, height=120, fps=24)
    scene = Scene("s", "a red box in a region", objects=(box,), camera=camera)
    red = []
    for regions in ({}, {"L": {"x": (0.4, 0.6), "y": (0.1, 0.3), "z": (0.0, 0.2)}}):
        world = PandaWorld(scene.with_regions(regions))
        image = world.render(camera)
        world.close()
        red.append(int(((image[..., 0] > 150) & (image[..., 1] < 80) & (image[..., 2] < 80)).sum()))
    assert red[0] > 100 and red[1] == red[0]  # TinyRenderer draws a translucent box opaque: it hid the box
