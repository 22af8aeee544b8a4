"""Skills with orientation: quaternion maths, demonstrations with `qx, qy, qz, qw`, the model on
R^3 x S^3, and the retrieved poses."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from stl_lfd import rotations
from stl_lfd.errors import SignalError
from stl_lfd.hsmm import learn, learn_from_folder, load_model, retrieve, save_model
from stl_lfd.hsmm.demos import with_checked_orientation
from stl_lfd.poses import Pose
from stl_lfd.rotations import QUATERNION_COLUMNS
from stl_lfd.signals import SignalTable, read_signal_csv, write_signal_csv
from tests.hsmm.pose_demos import pose_demos, write_pose_demos

RANDOM = Rotation.random(40, random_state=3).as_quat()
OTHERS = Rotation.random(40, random_state=4).as_quat()


def angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between rotations."""
    return np.linalg.norm(rotations.log_map(a, b), axis=-1)


def test_quaternion_maths_agrees_with_scipy():
    product = (Rotation.from_quat(RANDOM) * Rotation.from_quat(OTHERS)).as_quat()
    assert np.allclose(np.abs(np.sum(rotations.multiply(RANDOM, OTHERS) * product, axis=1)), 1.0)
    vectors = Rotation.from_quat(RANDOM).as_rotvec()
    assert np.allclose(rotations.to_rotvec(RANDOM), vectors) and np.allclose(np.abs(np.sum(rotations.from_rotvec(vectors) * RANDOM, axis=1)), 1.0)
    assert np.allclose(rotations.to_matrix(RANDOM), Rotation.from_quat(RANDOM).as_matrix())
    assert np.allclose(rotations.rotate(RANDOM, np.eye(3)[[0] * 40]), Rotation.from_quat(RANDOM).apply(np.eye(3)[0]))


def test_the_tangent_maps_invert_each_other_and_ignore_a_change_of_world_frame():
    tangent = rotations.log_map(RANDOM, OTHERS)
    assert np.all(np.linalg.norm(tangent, axis=1) <= np.pi + 1e-12)
    assert np.allclose(angle(rotations.exp_map(RANDOM, tangent), OTHERS), 0.0, atol=1e-9)
    world = Rotation.from_rotvec([0.3, -1.1, 2.0]).as_quat()
    moved = rotations.log_map(rotations.multiply(world, RANDOM), rotations.multiply(world, OTHERS))
    assert np.allclose(moved, tangent, atol=1e-12)


def test_transport_is_an_isometry_that_carries_the_geodesic_along():
    base, target = RANDOM[0], OTHERS[0]
    transport = rotations.transport(base, target)
    assert np.allclose(transport @ transport.T, np.eye(3))
    direction = rotations.log_map(base, target)
    assert np.allclose(transport @ direction, -rotations.log_map(target, base))  # the geodesic's velocity at its end


def test_the_weighted_mean_on_the_sphere_is_where_the_tangent_vectors_balance():
    cloud = rotations.multiply(RANDOM[5], Rotation.from_rotvec(0.4 * np.random.default_rng(0).normal(size=(60, 3))).as_quat())
    weights = np.random.default_rng(1).random(60)
    mean = rotations.weighted_mean(cloud, weights)
    assert np.linalg.norm(weights @ rotations.log_map(mean, cloud)) < 1e-9


def test_demonstrated_quaternions_are_made_continuous_and_bad_ones_are_refused(tmp_path):
    demo = pose_demos(1)[0]
    checked = with_checked_orientation(demo)
    quaternions = np.column_stack([checked.columns[name] for name in QUATERNION_COLUMNS])
    assert np.all(np.sum(quaternions[1:] * quaternions[:-1], axis=1) > 0)  # no sign flip left
    assert np.allclose(np.abs(np.sum(quaternions * np.column_stack([demo.columns[name] for name in QUATERNION_COLUMNS]), axis=1)), 1.0)
    slightly = SignalTable(demo.times, dict(demo.columns) | {"qw": demo.columns["qw"] * 1.0002}, demo.source)
    assert np.allclose(np.linalg.norm(np.column_stack([with_checked_orientation(slightly).columns[n] for n in QUATERNION_COLUMNS]), axis=1), 1.0)
    for change, message in (({"qw": np.where(np.arange(demo.samples) == 7, np.nan, demo.columns["qw"])}, "demo.csv:9: .* is not a unit quaternion"),
                            ({"qx": demo.columns["qx"] * 2}, "demo.csv:2: .* is not a unit quaternion \\(norm 2"),
                            ):  # fmt: skip
        with pytest.raises(SignalError, match=message):
            with_checked_orientation(SignalTable(demo.times, dict(demo.columns) | change, "demo.csv"))
    partial = SignalTable(demo.times, {name: values for name, values in demo.columns.items() if name != "qz"}, "demo.csv")
    with pytest.raises(SignalError, match="demo.csv: the orientation needs all of qx, qy, qz, qw \\(no column qz\\)"):
        with_checked_orientation(partial)


@pytest.fixture(scope="module")
def pose_skill():
    demos = [with_checked_orientation(demo) for demo in pose_demos()]
    model, sequences = learn(demos, 5)
    return model, demos


def test_a_pose_skill_has_rotation_vector_columns_relative_to_its_mean_orientation(pose_skill):
    model, demos = pose_skill
    assert model.signal_names_ == ["x", "y", "z", "rx", "ry", "rz"] and model.means_.shape == (5, 6) and model.covars_.shape == (5, 6, 6)
    every = np.concatenate([np.column_stack([demo.columns[name] for name in QUATERNION_COLUMNS]) for demo in demos])
    assert np.linalg.norm(rotations.log_map(model.orientation, every).sum(axis=0)) < 1e-6 * len(every)  # the samples' mean on the sphere
    first, last = model.orientations(model.means_[np.array(model.nominal_path())[[0, -1]]])
    assert np.degrees(rotations.tilt(first)) < 2 and abs(np.degrees(rotations.tilt(last)) - 90) < 2  # down, then a quarter turn


def test_the_retrieved_poses_pass_every_state_mean_and_turn_continuously(pose_skill):
    model, demos = pose_skill
    trajectory = retrieve(model, rate=240)
    assert trajectory.orientations.shape == (len(trajectory.times), 4)
    for state in model.nominal_path():
        mean_orientation = model.orientations(model.means_[state])
        closest = np.argmin(np.linalg.norm(trajectory.positions[:, :3] - model.means_[state, :3], axis=1))
        assert np.linalg.norm(trajectory.positions[closest, :3] - model.means_[state, :3]) < 0.002
        assert np.degrees(angle(trajectory.orientations[closest], mean_orientation)) < 2.0
    demonstrated = max(np.max(angle(q[:-1], q[1:])) for q in (np.column_stack([d.columns[n] for n in QUATERNION_COLUMNS]) for d in demos))
    steps_per_demo_sample = 240 / 50  # the retrieval's rate against the demonstrations'
    assert np.max(angle(trajectory.orientations[:-1], trajectory.orientations[1:])) * steps_per_demo_sample <= demonstrated


def test_a_rigid_motion_of_the_demonstrations_moves_the_retrieved_poses_by_it():
    motion, offset = Rotation.from_rotvec([0.4, -0.7, 1.2]), np.array([0.1, -0.05, 0.2])
    demos = [with_checked_orientation(demo) for demo in pose_demos()]
    moved = []
    for demo in demos:
        positions = motion.apply(np.column_stack([demo.columns[n] for n in "xyz"])) + offset
        quaternions = rotations.multiply(motion.as_quat(), np.column_stack([demo.columns[n] for n in QUATERNION_COLUMNS]))
        moved.append(SignalTable(demo.times, dict(zip("xyz", positions.T)) | dict(zip(QUATERNION_COLUMNS, quaternions.T)), demo.source))
    original, transformed = retrieve(learn(demos, 5)[0], rate=100), retrieve(learn(moved, 5)[0], rate=100)
    assert np.max(np.linalg.norm(motion.apply(original.positions[:, :3]) + offset - transformed.positions[:, :3], axis=1)) < 1e-6
    assert np.max(angle(rotations.multiply(motion.as_quat(), original.orientations), transformed.orientations)) < 1e-6


def test_a_pose_model_file_reads_back_and_retrieves_the_same(pose_skill, tmp_path):
    model, _ = pose_skill
    save_model(model, tmp_path / "pose.npz")
    again = load_model(tmp_path / "pose.npz")
    assert np.array_equal(again.orientation, model.orientation) and again.signal_names_ == model.signal_names_
    assert np.array_equal(retrieve(again, rate=100).orientations, retrieve(model, rate=100).orientations)


def test_pose_demonstration_files_learn_from_a_folder(tmp_path):
    write_pose_demos(tmp_path / "demos", count=3)
    model, _ = learn_from_folder(tmp_path / "demos", 5)
    assert model.orientation is not None and "rx" in model.signal_names_
    broken = read_signal_csv(tmp_path / "demos" / "demo_02.csv")
    write_signal_csv(SignalTable(broken.times, dict(broken.columns) | {"qx": broken.columns["qx"] + 0.5}, "x"), tmp_path / "demos" / "demo_02.csv")
    with pytest.raises(SignalError, match="demo_02.csv:2: .* is not a unit quaternion"):
        learn_from_folder(tmp_path / "demos", 5)


def test_more_em_starts_never_lose_likelihood():
    from stl_lfd.hsmm import HSMM
    from stl_lfd.hsmm.demos import resample

    demos = [with_checked_orientation(demo) for demo in pose_demos(seed=2)]
    sequences = [resample(demo, 0.02) for demo in demos]
    X, lengths, names = np.concatenate(sequences), [len(s) for s in sequences], list(demos[0].columns)
    single = HSMM(5).fit(X, lengths, 0.02, names)
    three = HSMM(5, n_init=3).fit(X, lengths, 0.02, names)
    assert three.monitor_.history[-1] >= single.monitor_.history[-1]


def moved(demo: SignalTable, pose: Pose) -> SignalTable:
    """`demo` (positions and orientations) moved by the rigid motion `pose`."""
    positions = np.column_stack([demo.columns[name] for name in "xyz"]) @ pose.rotation.T + np.array(pose.position)
    quaternions = rotations.multiply(pose.orientation, np.column_stack([demo.columns[name] for name in QUATERNION_COLUMNS]))
    return SignalTable(demo.times, dict(zip("xyz", positions.T)) | dict(zip(QUATERNION_COLUMNS, quaternions.T)), demo.source)


def full_pose(rng: np.random.Generator, spread: float = 0.05, turn: float = 0.3) -> Pose:
    return Pose(tuple(rng.normal(0.0, spread, 3)), quaternion=tuple(Rotation.from_rotvec(rng.normal(0.0, turn, 3)).as_quat()))


@pytest.fixture(scope="module")
def object_demos():
    """Pose demonstrations relative to an object, each with the object at another full 3-D pose."""
    rng = np.random.default_rng(0)
    local = [with_checked_orientation(demo) for demo in pose_demos(count=6)]
    poses = [full_pose(rng) for _ in local]
    return local, [moved(demo, pose) for demo, pose in zip(local, poses)], poses


def test_a_pose_skill_in_an_objects_frame_follows_the_object_in_position_and_orientation(object_demos):
    local, demos, poses = object_demos
    model, _ = learn(demos, 5, poses=[{"cup": pose} for pose in poses], frames=["cup"])
    assert model.feature_names == ["cup.x", "cup.y", "cup.z", "cup.rx", "cup.ry", "cup.rz"] and model.orientation.shape == (1, 4)
    new = full_pose(np.random.default_rng(7))
    at_new, in_object = retrieve(model, poses={"cup": new}, rate=100), retrieve(learn(local, 5)[0], rate=100)
    assert np.max(np.abs(at_new.positions[:, :3] - (in_object.positions[:, :3] @ new.rotation.T + np.array(new.position)))) < 1e-5
    assert np.max(angle(rotations.multiply(new.orientation, in_object.orientations), at_new.orientations)) < 1e-4


def test_moving_demonstrations_and_frames_rigidly_leaves_the_frame_local_model_and_moves_the_retrieved_poses(object_demos):
    _, demos, poses = object_demos
    model, _ = learn(demos, 5, poses=[{"cup": pose} for pose in poses], frames=["cup"])
    motion = Pose((0.1, -0.2, 0.05), quaternion=tuple(Rotation.from_rotvec([0.5, -0.9, 1.3]).as_quat()))
    moved_model, _ = learn([moved(demo, motion) for demo in demos], 5, poses=[{"cup": motion.compose(pose)} for pose in poses], frames=["cup"])
    assert np.max(np.abs(moved_model.means_ - model.means_)) < 1e-9 and np.max(np.abs(moved_model.covars_ - model.covars_)) < 1e-9
    new = full_pose(np.random.default_rng(7))
    original, transformed = retrieve(model, poses={"cup": new}, rate=100), retrieve(moved_model, poses={"cup": motion.compose(new)}, rate=100)
    assert np.max(np.abs(original.positions[:, :3] @ motion.rotation.T + np.array(motion.position) - transformed.positions[:, :3])) < 1e-6
    assert np.max(angle(rotations.multiply(motion.orientation, original.orientations), transformed.orientations)) < 1e-6


def test_frames_and_the_base_multiply_on_the_sphere_and_the_model_file_keeps_every_frames_reference(object_demos, tmp_path):
    _, demos, poses = object_demos
    model, _ = learn(demos, 5, poses=[{"cup": pose} for pose in poses], frames=["base", "cup"])
    assert model.orientation.shape == (2, 4)
    save_model(model, tmp_path / "tp.npz")
    again = load_model(tmp_path / "tp.npz")
    new = {"cup": full_pose(np.random.default_rng(3))}
    assert np.array_equal(retrieve(again, poses=new, rate=50).orientations, retrieve(model, poses=new, rate=50).orientations)
    trajectory = retrieve(model, poses=new, rate=240)
    assert np.max(angle(trajectory.orientations[:-1], trajectory.orientations[1:])) < np.radians(1)  # continuous
