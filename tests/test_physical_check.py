"""The benchmarks' physical check of a contact task's trial, on hand-made recordings."""

import numpy as np
import pytest

from benchmarks.physical import end_offset, flung, physically_inserted, scene_geometry, shaft_end
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable

HOLDER = Pose((0.55, 0.20, 0.04), 0.3)
GEOMETRY = scene_geometry("pick_insert")


def recording(end, tilt=0.0, jump=False):
    """The shaft from (0.45, -0.25, 0.08) to `end` in 10 s (or in one sample when `jump`)."""
    times = np.linspace(0.0, 10.0, 1001)
    phase = (times >= 5.0).astype(float) if jump else times / 10.0
    start = np.array([0.45, -0.25, 0.08])
    path = start + phase[:, None] * (np.asarray(end) - start)
    columns = {f"shaft_{axis}": path[:, index] for index, axis in enumerate("xyz")}
    columns |= {"holder_x": np.full(times.size, 0.55), "holder_y": np.full(times.size, 0.20), "holder_z": np.full(times.size, 0.04)}
    columns["shaft_tilt"] = np.full(times.size, tilt)
    return SignalTable(times, columns, source="made")


@pytest.mark.parametrize(
    "end, tilt, jump, where, inside",
    [
        ((0.553, 0.198, 0.08), 0.0, False, "inserted", True),  # upright, 3 mm off the axis, bottom on the table
        ((0.553, 0.198, 0.08), 0.0, True, "inserted", False),  # got there in one sample (46 m/s): flung
        ((0.553, 0.198, 0.08), 0.1, False, "other", False),  # 6 degrees off upright
        ((0.55, 0.20, 0.14), 0.0, False, "other", False),  # standing on the rim
        ((0.52, 0.20, 0.08), 0.0, False, "other", False),  # beside the hole
        ((0.80, 0.20, 0.03), 1.57, False, "thrown", False),  # off the table
    ],
)
def test_where_the_shaft_ends(end, tilt, jump, where, inside):
    signals = recording(end, tilt, jump)
    assert shaft_end(signals, HOLDER, GEOMETRY) == where
    assert flung(signals) == jump
    assert physically_inserted(signals, HOLDER, GEOMETRY) == inside


def test_a_shaft_in_a_corner_of_the_hole_is_inserted_beyond_the_specs_offset():
    corner = HOLDER.to_base(np.array([[0.0055, 0.0055, 0.04]]))[0]  # 5.5 mm off the axis in both of the holder's axes
    signals = recording(corner)
    assert physically_inserted(signals, HOLDER, GEOMETRY) and end_offset(signals) == pytest.approx(0.0055 * np.sqrt(2), abs=1e-9)


def test_the_geometry_is_read_from_the_scene_files():
    for scene in ("pick_insert", "pick_reorient_insert"):
        geometry = scene_geometry(scene)
        assert (geometry.table_top, geometry.table_x, geometry.table_y) == (0.02, (0.25, 0.75), (-0.45, 0.45))
        assert (geometry.shaft_half_length, geometry.holder_height, geometry.clearance) == (0.06, 0.02, 0.006)  # a 32 mm hole, a 20 mm shaft
