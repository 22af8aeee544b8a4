"""The independent physical check of the contact tasks: where the shaft ends, read from its
recorded pose and the holder's (not from the outcome signals the specs use), so that the
specs' verdicts can be checked against it.

A trial's shaft ends
  THROWN    more than 15 cm (in x-y) from both the hole's centre and where the shaft started,
            or off the table (its centre below the table's top less 5 mm, or outside its x-y);
  INSERTED  in the hole: its bottom below the holder's top, its centre within the clearance
            of the hole's axis in the holder's x and y (6 mm in the bundled scenes), and
            upright within 3 degrees;
  OTHER     anywhere else (on the table, on the holder, still in the hand).
It was FLUNG when its centre moved faster than 1 m/s at some instant (the hand never goes
faster; a shaft that does was thrown or dropped). PHYSICALLY INSERTED: it ends INSERTED and was
never flung. The table, the shaft and the holder's walls are read from the task's scene file
(`scene_geometry`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from stl_lfd import Pose

THROW_DISTANCE, BELOW_TOP = 0.15, 0.005
FLUNG_SPEED = 1.0  # m/s


@dataclass(frozen=True)
class Geometry:
    """What the check needs of a contact scene, read from its scene file.

    Attributes:
        table_top: the table's top (m); table_x, table_y: its extent.
        shaft_half_length: half the shaft's length (a cylinder's second size).
        holder_height: how far the holder's walls rise above the holder frame's origin.
        clearance: the hole's half width less the shaft's radius (the room each side).
    """

    table_top: float
    table_x: tuple[float, float]
    table_y: tuple[float, float]
    shaft_half_length: float
    holder_height: float
    clearance: float


@lru_cache(maxsize=8)
def scene_geometry(scene_name: str) -> Geometry:
    """The `Geometry` of a scene with a box `table`, a cylinder shaft (frame `shaft`) and box
    walls (frame `holder`) around a hole on the holder frame's vertical."""
    from stl_lfd.sim import load_scene

    scene = load_scene(scene_name)
    objects = {item.name: item for item in scene.objects}
    frames = {frame.name: frame for frame in scene.frames}
    table, shaft = objects["table"], objects[frames["shaft"].objects[0]]
    holder = frames["holder"]
    walls = [objects[name] for name in holder.objects]
    local = holder.pose.from_base(np.array([wall.position for wall in walls]))  # wall centres in the holder's frame
    # A wall bounds the hole where its inner face is: the nearer of its faces along x and y.
    half_width = min(max(abs(centre[0]) - wall.size[0], abs(centre[1]) - wall.size[1]) for centre, wall in zip(local, walls))
    height = max(centre[2] + wall.size[2] for centre, wall in zip(local, walls))
    lengths = (table.position[2] + table.size[2], shaft.size[1] / 2, height, half_width - shaft.size[0])
    table_top, shaft_half_length, holder_height, clearance = (round(float(length), 9) for length in lengths)  # to the nanometre: 6 mm is 6 mm
    return Geometry(
        table_top=table_top,
        table_x=(table.position[0] - table.size[0], table.position[0] + table.size[0]),
        table_y=(table.position[1] - table.size[1], table.position[1] + table.size[1]),
        shaft_half_length=shaft_half_length,
        holder_height=holder_height,
        clearance=clearance,
    )


def is_contact_task(task: Any) -> bool:
    """Whether `task`'s scene has a shaft that goes into the holder's hole, at one placement
    (with several, the recorded signals are the worst placement's, whose holder's turn they do
    not name, so the check cannot be made)."""
    from stl_lfd.sim import load_scene

    return len(task.placements) <= 1 and any(frame.name == "shaft" and frame.into == "holder" for frame in load_scene(task.scene).frames)


def holder_pose(task: Any) -> Pose:
    """The holder frame's pose in `task` (its placement, else the scene's); a task with several
    placements has no one holder pose (ValueError)."""
    from stl_lfd.sim import load_scene

    if len(task.placements) > 1:
        raise ValueError(f"{task.name}: several placements; the recorded signals do not say which holder pose they are at")
    placed = task.placements[0] if task.placements else {}
    return placed.get("holder") or load_scene(task.scene).frame_poses["holder"]


def inserted(signals: Any, holder: Pose, geometry: Geometry) -> tuple[bool, str]:
    """Whether the shaft ends in the hole, and how it ends (mm and degrees, holder frame)."""
    end = {name: values[-1] for name, values in signals.columns.items()}
    local = holder.from_base(np.array([[end["shaft_x"], end["shaft_y"], end["shaft_z"]]]))[0]
    tilt = np.degrees(end["shaft_tilt"])
    bottom = local[2] - geometry.shaft_half_length * np.cos(end["shaft_tilt"])
    clearance = geometry.clearance
    ok = bottom < geometry.holder_height and abs(local[0]) < clearance and abs(local[1]) < clearance and tilt < 3.0
    return bool(ok), f"({1000 * local[0]:+.1f}, {1000 * local[1]:+.1f}) mm, tilt {tilt:.1f} deg"


def end_offset(signals: Any) -> float:
    """How far (m, in x-y) the shaft's centre ends from the hole's axis: a shaft in a corner of
    the square hole is inserted up to 8.5 mm off it, while the specs' `shaft_offset` asks for
    less than 6 mm."""
    columns = signals.columns
    return float(np.hypot(columns["shaft_x"][-1] - columns["holder_x"][-1], columns["shaft_y"][-1] - columns["holder_y"][-1]))


def shaft_end(signals: Any, holder: Pose, geometry: Geometry) -> str:
    """`thrown`, `inserted` or `other`: where the shaft ends (`holder`: the hole frame's pose,
    whose yaw the recorded signals do not carry; `geometry`: the scene's)."""
    columns = signals.columns
    x, y, z = (float(columns[f"shaft_{axis}"][-1]) for axis in "xyz")
    hole = np.array([columns["holder_x"][-1], columns["holder_y"][-1]])
    start = np.array([columns["shaft_x"][0], columns["shaft_y"][0]])
    far = min(np.hypot(*(np.array([x, y]) - hole)), np.hypot(*(np.array([x, y]) - start))) > THROW_DISTANCE
    table_x, table_y = geometry.table_x, geometry.table_y
    off_table = z < geometry.table_top - BELOW_TOP or not (table_x[0] <= x <= table_x[1] and table_y[0] <= y <= table_y[1])
    if far or off_table:
        return "thrown"
    hole_frame = Pose((float(hole[0]), float(hole[1]), float(columns["holder_z"][-1])), holder.yaw, holder.quaternion)
    return "inserted" if inserted(signals, hole_frame, geometry)[0] else "other"


def flung(signals: Any) -> bool:
    """Whether the shaft's centre ever moved faster than `FLUNG_SPEED` (from its recorded positions)."""
    positions = np.column_stack([signals.columns[f"shaft_{axis}"] for axis in "xyz"])
    velocities = np.diff(positions, axis=0) / np.diff(signals.times)[:, None]
    return bool(np.linalg.norm(velocities, axis=1).max(initial=0.0) > FLUNG_SPEED)


def physically_inserted(signals: Any, holder: Pose, geometry: Geometry) -> bool:
    """The shaft ends in the hole and was never flung."""
    return shaft_end(signals, holder, geometry) == "inserted" and not flung(signals)
