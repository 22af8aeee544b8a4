"""The independent physical check of the contact tasks: where the shaft ends, read from its
recorded pose and the holder's (not from the outcome signals the specs use), so that the
specs' verdicts can be checked against it.

A trial's shaft ends
  THROWN    more than 15 cm (in x-y) from both the hole's centre and where the shaft started,
            or off the table (its centre below the table's top less 5 mm, or outside its x-y);
  INSERTED  in the hole: its bottom below the holder's top, its centre within the clearance
            (6 mm) of the hole's axis in the holder's x and y, and upright within 3 degrees;
  OTHER     anywhere else (on the table, on the holder, still in the hand).
It was FLUNG when its centre moved faster than 1 m/s at some instant (the hand never goes
faster; a shaft that does was thrown or dropped). PHYSICALLY INSERTED: it ends INSERTED and was
never flung.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from stl_lfd import Pose

# The scenes' table: a box centred at (0.5, 0, 0.01) with half extents (0.25, 0.45, 0.01).
TABLE_TOP, TABLE_X, TABLE_Y = 0.02, (0.25, 0.75), (-0.45, 0.45)
THROW_DISTANCE, BELOW_TOP = 0.15, 0.005
FLUNG_SPEED = 1.0  # m/s
# The shaft (120 mm long) and the holder (walls 4 cm high on a 2 cm table: top at 6 cm; a 32 mm
# hole for a 20 mm shaft: 6 mm of clearance each side).
SHAFT_HALF_LENGTH, HOLDER_TOP, CLEARANCE = 0.06, 0.06, 0.006


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


def inserted(signals: Any, holder: Pose) -> tuple[bool, str]:
    """Whether the shaft ends in the hole, and how it ends (mm and degrees, holder frame)."""
    end = {name: values[-1] for name, values in signals.columns.items()}
    local = holder.from_base(np.array([[end["shaft_x"], end["shaft_y"], end["shaft_z"]]]))[0]
    tilt = np.degrees(end["shaft_tilt"])
    bottom = end["shaft_z"] - SHAFT_HALF_LENGTH * np.cos(end["shaft_tilt"])
    ok = bottom < HOLDER_TOP and abs(local[0]) < CLEARANCE and abs(local[1]) < CLEARANCE and tilt < 3.0
    return bool(ok), f"({1000 * local[0]:+.1f}, {1000 * local[1]:+.1f}) mm, tilt {tilt:.1f} deg"


def end_offset(signals: Any) -> float:
    """How far (m, in x-y) the shaft's centre ends from the hole's axis: a shaft in a corner of
    the square hole is inserted up to 8.5 mm off it, while the specs' `shaft_offset` asks for
    less than 6 mm."""
    columns = signals.columns
    return float(np.hypot(columns["shaft_x"][-1] - columns["holder_x"][-1], columns["shaft_y"][-1] - columns["holder_y"][-1]))


def shaft_end(signals: Any, holder: Pose) -> str:
    """`thrown`, `inserted` or `other`: where the shaft ends (`holder`: the hole frame's pose,
    whose yaw the recorded signals do not carry)."""
    columns = signals.columns
    x, y, z = (float(columns[f"shaft_{axis}"][-1]) for axis in "xyz")
    hole = np.array([columns["holder_x"][-1], columns["holder_y"][-1]])
    start = np.array([columns["shaft_x"][0], columns["shaft_y"][0]])
    far = min(np.hypot(*(np.array([x, y]) - hole)), np.hypot(*(np.array([x, y]) - start))) > THROW_DISTANCE
    off_table = z < TABLE_TOP - BELOW_TOP or not (TABLE_X[0] <= x <= TABLE_X[1] and TABLE_Y[0] <= y <= TABLE_Y[1])
    if far or off_table:
        return "thrown"
    hole_frame = Pose((float(hole[0]), float(hole[1]), float(columns["holder_z"][-1])), holder.yaw, holder.quaternion)
    return "inserted" if inserted(signals, hole_frame)[0] else "other"


def flung(signals: Any) -> bool:
    """Whether the shaft's centre ever moved faster than `FLUNG_SPEED` (from its recorded positions)."""
    positions = np.column_stack([signals.columns[f"shaft_{axis}"] for axis in "xyz"])
    velocities = np.diff(positions, axis=0) / np.diff(signals.times)[:, None]
    return bool(np.linalg.norm(velocities, axis=1).max(initial=0.0) > FLUNG_SPEED)


def physically_inserted(signals: Any, holder: Pose) -> bool:
    """The shaft ends in the hole and was never flung."""
    return shaft_end(signals, holder) == "inserted" and not flung(signals)
