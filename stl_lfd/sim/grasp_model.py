"""Where a grasped object sits in the hand, learned from executions: a grasp model.

The kinematic backend carries a grasped object rigidly in the pose it had in the hand at the
grasp. A real grasp (and the compliant robot's friction grasp) is not that rigid: closing
fingers push the object into place, and lifting a long object by its middle lets it turn a few
degrees about the fingers' axis. `GraspModel` learns, per frame that moves with an object, the
object's pose in the hand while it is carried (its position and orientation in the hand's
frame, the median over the second half of each execution's held samples, after the fingers
have settled and before the release), so that a prediction carries the object there.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable
from stl_lfd.sim.scene import Scene

# Below these departures (m, rad) of the carried pose from the pose at the grasp, the grasp is
# taken as rigid: a prediction carrying the object elsewhere would change nothing a spec can tell.
RIGID_WITHIN = (0.001, 0.01)
SETTLE_SECONDS = 1.0  # a prediction moves the object from its pose at the grasp to the learned one over this time
FEWEST_HELD = 10  # held samples an execution needs to tell where the object sits


@dataclass(frozen=True)
class InHand:
    """An object's pose in the hand's frame: `position` (`3`, m) of its frame's origin and
    `orientation` (`4`, unit quaternion, scalar last) of the object."""

    position: np.ndarray
    orientation: np.ndarray


@dataclass
class GraspModel:
    """Where each carried frame's object sits in the hand (see the module's docstring).

    Attributes (after `fit`):
        in_hand_: frame name -> its learned `InHand` pose (frames never held: absent).
        departure_: frame name -> `(m, rad)`: how far the learned pose is from the pose at the
            grasp, averaged over the executions (what a rigid grasp would carry).
    """

    in_hand_: dict[str, InHand] = field(default_factory=dict)
    departure_: dict[str, tuple[float, float]] = field(default_factory=dict)

    def fit(self, recordings: Sequence[SignalTable], scene: Scene) -> "GraspModel":
        """Learn from the recorded signals of executions in `scene` (recordings without the
        hand's or the objects' orientations, or without a grasp, teach nothing)."""
        return self.fit_poses([carried_poses(signals, scene) for signals in recordings])

    def fit_poses(self, executions: Sequence[dict[str, tuple[InHand, InHand]]]) -> "GraspModel":
        """Learn from each execution's `carried_poses`."""
        self.in_hand_, self.departure_ = {}, {}
        for name in dict.fromkeys(name for poses in executions for name in poses):
            carried, at_grasp = zip(*(poses[name] for poses in executions if name in poses))
            learned = InHand(
                np.mean([pose.position for pose in carried], axis=0),
                rotations.weighted_mean(rotations.continuous(np.array([pose.orientation for pose in carried]))),
            )
            self.in_hand_[name] = learned
            self.departure_[name] = (
                float(np.mean([np.linalg.norm(learned.position - pose.position) for pose in at_grasp])),
                float(np.mean([np.linalg.norm(rotations.log_map(pose.orientation, learned.orientation)) for pose in at_grasp])),
            )
        return self

    @property
    def rigid(self) -> bool:
        """Whether every learned pose is within RIGID_WITHIN of the pose at the grasp."""
        return all(distance <= RIGID_WITHIN[0] and angle <= RIGID_WITHIN[1] for distance, angle in self.departure_.values())

    def to_dict(self) -> dict:
        """Plain values, for JSON."""
        return {
            name: {"position": pose.position.tolist(), "orientation": pose.orientation.tolist(), "departure": list(self.departure_[name])}
            for name, pose in self.in_hand_.items()
        }

    @classmethod
    def from_dict(cls, data: dict) -> "GraspModel":
        return cls(
            {name: InHand(np.asarray(value["position"], dtype=float), np.asarray(value["orientation"], dtype=float)) for name, value in data.items()},
            {name: (float(value["departure"][0]), float(value["departure"][1])) for name, value in data.items()},
        )


def carried_poses(signals: SignalTable, scene: Scene) -> dict[str, tuple[InHand, InHand]]:
    """Per frame of `scene` that moves with an object and was held long enough in `signals`: its
    median pose in the hand over the second half of its held samples, and the pose a rigid
    grasp would hold it in (where it lay at the start, in the hand at the first held sample).
    Frames whose poses the signals cannot tell are left out."""
    poses = {}
    for frame in scene.moving_frames:
        found = _carried_pose(signals, frame.name)
        if found is not None:
            poses[frame.name] = found
    return poses


def _carried_pose(signals: SignalTable, name: str) -> tuple[InHand, InHand] | None:
    """`carried_poses` of frame `name`, or None."""
    columns = signals.columns
    needed = ("x", "y", "z", *QUATERNION_COLUMNS, f"{name}_held", *(f"{name}_{suffix}" for suffix in ("x", "y", "z", *QUATERNION_COLUMNS)))
    if any(column not in columns for column in needed):
        return None
    held = np.flatnonzero(columns[f"{name}_held"] > 0.5)
    if len(held) < FEWEST_HELD:
        return None

    def read(prefix: str, components: Sequence[str], samples: np.ndarray) -> np.ndarray:
        return np.column_stack([columns[prefix + component][samples] for component in components])

    hand_positions, hand_turns = read("", "xyz", held), read("", QUATERNION_COLUMNS, held)
    object_positions, object_turns = read(f"{name}_", "xyz", held), read(f"{name}_", QUATERNION_COLUMNS, held)
    local_positions = rotations.rotate(rotations.conjugate(hand_turns), object_positions - hand_positions)
    local_turns = rotations.continuous(rotations.multiply(rotations.conjugate(hand_turns), object_turns))
    later = slice(len(held) // 2, None)
    carried = InHand(np.median(local_positions[later], axis=0), rotations.weighted_mean(local_turns[later]))
    # what a rigid grasp carries: the object as it lay before the hand came (the first sample), in the hand as it closed
    lying_position, lying_turn = read(f"{name}_", "xyz", np.array([0]))[0], read(f"{name}_", QUATERNION_COLUMNS, np.array([0]))[0]
    into_hand = rotations.conjugate(hand_turns[0])
    at_grasp = InHand(rotations.rotate(into_hand, lying_position - hand_positions[0]), rotations.multiply(into_hand, lying_turn))
    return carried, at_grasp
