"""The grasp model: where a carried object sits in the hand, learned from recorded signals, and
the kinematic prediction that carries it there."""

import json

import numpy as np
import pytest

import stl_lfd.rotations as rotations
from stl_lfd.sim import execute, load_scene
from stl_lfd.sim.grasp_model import GraspModel, InHand, carried_poses
from stl_lfd.sim.tracking_model import PredictingBackend, TrackingModel
from tests.sim.test_outcome import carry_into_hole

SCENE = load_scene("pick_insert")
GRASP, HOLE = np.array([0.45, -0.25, 0.11]), np.array([0.55, 0.20, 0.11])
REFERENCE = carry_into_hole(SCENE, GRASP, HOLE)  # grasp at 2 s, release at 8 s, hand straight down


def carried(in_hand=None):
    backend = PredictingBackend(TrackingModel(), GraspModel(in_hand or {}))
    return backend.run(REFERENCE, SCENE, 100.0).signals


def test_a_rigid_grasp_is_learned_as_rigid():
    signals = execute(REFERENCE, SCENE, "kinematic", rate=100.0).signals
    model = GraspModel().fit([signals], SCENE)
    assert list(model.in_hand_) == ["shaft"] and model.rigid
    # the shaft's frame origin (its centre) 3 cm below the grasp point, upright in a hand pointing down
    assert model.in_hand_["shaft"].position == pytest.approx([0.0, 0.0, 0.03], abs=1e-9)
    assert model.departure_["shaft"] == pytest.approx((0.0, 0.0), abs=1e-9)


def test_the_prediction_carries_the_object_where_it_sits_in_the_hand_and_the_model_learns_it_back():
    rigid = GraspModel().fit([carried()], SCENE).in_hand_["shaft"]
    turned = InHand(rigid.position + [0.002, 0.0, 0.0], rotations.multiply(rigid.orientation, rotations.from_euler(0.05, 0.0, 0.0)))
    signals = carried({"shaft": turned})
    times, columns = signals.times, signals.columns
    settled = (times > 3.2) & (times < 7.9)
    assert columns["shaft_tilt"][settled] == pytest.approx(0.05, abs=1e-6)
    assert columns["shaft_tilt"][(times > 0.5) & (times < 1.9)] == pytest.approx(0.0, abs=1e-9)
    # settling over a second: no jump a speed limit on the let-go shaft could see
    assert columns["shaft_speed"][columns["shaft_held"] < 0.5].max() < 0.2
    learned = GraspModel().fit([signals], SCENE)
    assert not learned.rigid
    assert learned.in_hand_["shaft"].position == pytest.approx(turned.position, abs=1e-6)
    assert np.linalg.norm(rotations.log_map(learned.in_hand_["shaft"].orientation, turned.orientation)) < 1e-6
    assert learned.departure_["shaft"] == pytest.approx((0.002, 0.05), abs=1e-6)


def test_recordings_without_orientations_or_grasps_teach_nothing():
    signals = execute(REFERENCE, SCENE, "kinematic", rate=100.0).signals
    without = type(signals)(signals.times, {name: values for name, values in signals.columns.items() if name != "shaft_qw"})
    never_held = type(signals)(signals.times, {**signals.columns, "shaft_held": np.zeros(signals.samples)})
    assert carried_poses(without, SCENE) == {} and carried_poses(never_held, SCENE) == {}
    assert GraspModel().fit([without, never_held], SCENE).in_hand_ == {}


def test_the_model_survives_json():
    rigid = GraspModel().fit([carried()], SCENE).in_hand_["shaft"]
    model = GraspModel().fit([carried({"shaft": InHand(rigid.position + [0.0, 0.003, 0.0], rigid.orientation)})], SCENE)
    again = GraspModel.from_dict(json.loads(json.dumps(model.to_dict())))
    assert again.in_hand_["shaft"].position == pytest.approx(model.in_hand_["shaft"].position)
    assert again.in_hand_["shaft"].orientation == pytest.approx(model.in_hand_["shaft"].orientation)
    assert again.departure_["shaft"] == pytest.approx(model.departure_["shaft"]) and not again.rigid


def test_method_plan_predicts_through_a_grasp_that_is_not_rigid_even_when_the_arm_follows_the_plan():
    from stl_lfd.optim.tracking_fit import used

    rigid = GraspModel().fit([carried()], SCENE)
    moved = GraspModel().fit([carried({"shaft": InHand(rigid.in_hand_["shaft"].position + [0.0, 0.0, 0.004], rigid.in_hand_["shaft"].orientation)})], SCENE)
    follows = TrackingModel()  # the plan itself
    assert not used(follows) and not used(follows, rigid) and used(follows, moved)
