"""What a backend observed at each instant of a rollout, before it becomes signal columns
(`recorder.py`) and clearances (`clearance.py`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Steps:
    """What a backend observed at `S` instants.

    Attributes:
        times: `S` seconds.
        positions: `S x 3` grasp-target positions (m, base frame).
        orientations: `S x 4` hand orientations (unit quaternions x, y, z, w).
        gripper: `S` finger openings (m).
        wrench: `S x 6` external force (N) and torque (Nm) at the wrist, base frame.
        frame_positions: `S x F x 3` positions of the scene's frames.
        frame_orientations: `S x F x 4` orientations of the frames' first objects.
        frame_held: `S x F`: 1 where both fingers touch the object a frame moves with, else 0.
    """

    times: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    gripper: np.ndarray
    wrench: np.ndarray
    frame_positions: np.ndarray
    frame_orientations: np.ndarray
    frame_held: np.ndarray
