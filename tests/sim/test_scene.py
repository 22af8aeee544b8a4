from pathlib import Path

import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.sim import builtin_scenes, load_scene


def test_free_space_is_built_in():
    assert "free_space" in builtin_scenes()
    scene = load_scene("free_space")
    assert scene.name == "free_space" and scene.objects == () and scene.regions == ()
    assert 0 < scene.control.position_gain <= 1


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
        ("description: d\ncontrol: {position_gain: 3}\n", r"'control.position_gain' must be in \(0, 1\]"),
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
