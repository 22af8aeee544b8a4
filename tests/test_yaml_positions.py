"""Errors about a YAML file's keys name the line and column of the key (or of its nearest
parent when the key is missing)."""

from __future__ import annotations

import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.yamlfile import check_keys, number, read_yaml, vector

TEXT = """\
name: demo
optimizer:
  method: plan
  trails: 32
frames:
  - position: [0.1, 0.2]
  - position: [0.1, 0.2, 0.3]
    size: big
"""


@pytest.fixture
def task(tmp_path):
    path = tmp_path / "task.yaml"
    path.write_text(TEXT)
    return path, read_yaml(path)


def test_an_unknown_key_is_shown_where_it_is(task):
    path, data = task
    with pytest.raises(ConfigError) as error:
        check_keys(data["optimizer"], ("method", "trials"), path, "optimizer")
    assert str(error.value).startswith(f"{path}:4:3: unknown key 'optimizer.trails'")


def test_a_bad_value_in_a_list_is_shown_at_its_item(task):
    path, data = task
    with pytest.raises(ConfigError, match=r":6:5: 'frames\[0\].position' must be a list of 3 numbers"):
        vector(data["frames"][0]["position"], 3, path, "frames[0].position")
    with pytest.raises(ConfigError, match=r":8:5: 'frames\[1\].size' must be a number"):
        number(data["frames"][1]["size"], path, "frames[1].size")


def test_a_missing_key_is_shown_at_its_parent(task):
    path, data = task
    with pytest.raises(ConfigError) as error:
        check_keys(data["optimizer"], ("method", "trails", "seed"), path, "optimizer", required=("seed",))
    assert str(error.value) == f"{path}:2:1: missing key 'optimizer.seed'"


def test_messages_about_other_files_or_no_key_are_left_alone(task, tmp_path):
    path, _ = task
    assert str(ConfigError(f"{path}: expected a mapping")) == f"{path}: expected a mapping"
    other = tmp_path / "other.yaml"
    assert str(ConfigError(f"{other}: 'name' must be a string")) == f"{other}: 'name' must be a string"
