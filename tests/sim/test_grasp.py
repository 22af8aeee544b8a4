"""Grasp and release in the pick_insert scene on both simulated Pandas, on a scripted reference
(no skill model): the fingers hold the shaft by friction, the compliant arm yields to the holder."""

import warnings

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.errors import ExecutionError
from stl_lfd.sim import Reference, TrackingWarning, execute, load_scene
from stl_lfd.sim.grasp_model import GraspModel

SCENE = load_scene("pick_insert")
GRASP = np.array([0.45, -0.25, 0.11])
HOLE = np.array([0.55, 0.20, 0.115])


def minimum_jerk(times, waypoints):
    positions = np.repeat(np.asarray(waypoints[0][1], float)[None], times.size, axis=0)
    for (t0, p0), (t1, p1) in zip(waypoints[:-1], waypoints[1:]):
        inside = (times >= t0) & (times <= t1)
        phase = (times[inside] - t0) / (t1 - t0)
        positions[inside] = np.asarray(p0) + (np.asarray(p1) - np.asarray(p0)) * (10 * phase**3 - 15 * phase**4 + 6 * phase**5)[:, None]
    positions[times > waypoints[-1][0]] = waypoints[-1][1]
    return positions


def pick_and_place(offset=(0.0, 0.0), grasp_at=GRASP):
    """Down to the shaft, grasp at 3 s, carry over the holder (offset in x, y), lower it
    straight down, release at 11 s, move up."""
    target = HOLE + np.array([*offset, 0.0])
    above_grasp, above_hole = grasp_at + [0, 0, 0.14], target + [0, 0, 0.19]
    waypoints = [
        (0, above_grasp),
        (2, grasp_at),
        (3.5, grasp_at),
        (5, above_grasp),
        (8, above_hole),
        (9, above_hole),
        (10.5, target),
        (11.5, target),
        (13, above_hole),
    ]
    times = np.arange(0, 13.5, 1 / 240)
    gripper = np.where((times >= 3.0) & (times < 11.0), 0.0, 0.08)
    return Reference(times, minimum_jerk(times, waypoints), gripper, ((3.0, "grasp"), (11.0, "release")))


ENGINES = ["pybullet", "mujoco"]


class ShaftTracker:
    """Observer recording the shaft and hand positions at every step."""

    def __init__(self):
        self.times, self.shaft, self.hand = [], [], []

    def __call__(self, time, world):
        self.times.append(time)
        self.shaft.append(world.object_poses()["shaft"][0])
        self.hand.append(world.hand_pose()[0])


@pytest.fixture(scope="module", params=ENGINES)
def aligned(request):
    tracker = ShaftTracker()
    rollout = execute(pick_and_place(), SCENE, request.param, observer=tracker)
    return rollout, tracker


@pytest.mark.slow
def test_the_grasped_shaft_travels_with_the_hand(aligned):
    _, tracker = aligned
    times, shaft, hand = np.array(tracker.times), np.array(tracker.shaft), np.array(tracker.hand)
    transport = (times > 4.0) & (times < 10.0)
    offsets = shaft[transport] - hand[transport]
    assert np.ptp(offsets, axis=0).max() < 0.003  # held by friction: the offset varies by under 3 mm
    assert np.linalg.norm(shaft[transport][-1] - shaft[transport][0]) > 0.4  # and it went a long way


@pytest.mark.slow
def test_release_leaves_the_shaft_standing_in_the_holder(aligned):
    _, tracker = aligned
    final = tracker.shaft[-1]
    assert np.allclose(final[:2], HOLE[:2], atol=0.006)
    assert final[2] == pytest.approx(0.08, abs=0.005)  # standing on the table inside the hole


@pytest.mark.slow
def test_the_outcome_signals_see_the_shaft_held_carried_and_let_go_in_the_hole(aligned):
    rollout, _ = aligned
    columns, times = rollout.signals.columns, rollout.signals.times
    held = columns["shaft_held"]
    assert held[times < 2.9].max() == 0.0 and held[(times > 3.5) & (times < 10.9)].min() == 1.0 and held[times > 11.5].max() == 0.0
    assert columns["shaft_speed"][(times > 6.0) & (times < 7.0)].min() > 0.05  # carried
    assert columns["shaft_speed"][times > 12.0].max() < 0.01  # at rest once let go
    assert columns["shaft_depth"][-1] == pytest.approx(0.04, abs=0.003)  # its bottom on the table, 4 cm below the rim
    assert columns["shaft_offset"][-1] < 0.006
    turns = np.column_stack([columns[f"shaft_{component}"] for component in ("qx", "qy", "qz", "qw")])
    assert np.allclose(np.linalg.norm(turns, axis=1), 1.0) and np.allclose(rotations.uprightness(turns), columns["shaft_tilt"], atol=1e-3)
    # a firm grasp of an upright shaft by a hand pointing down: it sits in the hand as it was taken
    grasp = GraspModel().fit([rollout.signals], SCENE)
    assert grasp.departure_["shaft"][0] < 0.003 and grasp.departure_["shaft"][1] < 0.05


@pytest.mark.slow
def test_the_wrist_feels_no_force_in_free_motion_nor_while_carrying(aligned):
    rollout, _ = aligned
    force, times = rollout.signals.columns["force"], rollout.signals.times
    assert force[times < 1.9].max() < 1.0  # moving down to the shaft, touching nothing
    assert force[(times > 5.5) & (times < 9.5)].max() < 1.0  # carrying it: its weight is the declared load, not contact
    assert force.max() < 5.0  # set down in the hole without pushing


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_a_misaligned_insertion_pushes_on_the_holder_as_a_compliant_arm_does(engine):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)  # blocked by the holder, as intended
        rollout = execute(pick_and_place(offset=(0.012, 0.0)), SCENE, engine)
    force, times = rollout.signals.columns["force"], rollout.signals.times
    pushing = force[(times > 9.0) & (times < 11.0)]
    # the hand is sent 7.5 cm below the rim: a 400 N/m spring, not a position-controlled arm
    assert 5.0 < pushing.max() < 60.0
    columns = rollout.signals.columns
    assert columns["shaft_depth"][-1] < 0.01 or columns["shaft_offset"][-1] > 0.006  # not in the hole


@pytest.mark.parametrize("engine", ENGINES)
def test_a_grasp_with_nothing_in_reach_fails_the_rollout(engine):
    with pytest.raises(ExecutionError, match=r"grasp at t = 3.00 s: nothing within 30 mm of the hand"):
        execute(pick_and_place(grasp_at=GRASP + [0.0, 0.1, 0.0]), SCENE, engine)


@pytest.mark.parametrize(
    "shape, size, point, distance",
    [
        ("box", (0.1, 0.05, 0.05), (0.0, 0.0, 0.0), 0.0),  # half extents: inside
        ("box", (0.1, 0.05, 0.05), (0.13, 0.0, 0.0), 0.03),
        ("cylinder", (0.01, 0.12), (0.0, 0.04, 0.0), 0.03),  # (radius, height), beside
        ("cylinder", (0.01, 0.12), (0.0, 0.0, 0.1), 0.04),  # above its top
        ("sphere", (0.05,), (0.0, 0.0, 0.08), 0.03),
    ],
)
def test_distance_to_shapes(shape, size, point, distance):
    from stl_lfd.sim.shapes import distance_to_shape

    assert distance_to_shape(shape, size, np.array(point)) == pytest.approx(distance)


def test_the_distance_to_an_object_follows_its_pose():
    from stl_lfd.rotations import from_euler
    from stl_lfd.sim.scene import SceneObject

    lying = SceneObject("shaft", "cylinder", (0.01, 0.12), (0.5, 0.0, 0.05), orientation=(np.pi / 2, 0.0, 0.0), mass=0.05)
    assert lying.distance((0.5, 0.05, 0.05)) == pytest.approx(0.0)  # inside, along its axis (y)
    assert lying.distance((0.5, 0.0, 0.09)) == pytest.approx(0.03)  # above its side
    assert lying.distance((0.5, 0.0, 0.09), (0.5, 0.0, 0.05), from_euler(0.0, 0.0, 0.0)) == pytest.approx(0.0)  # stood upright
