"""TP-HSMM: frame sidecars, learning in object frames, retrieval for new object poses."""

import numpy as np
import pytest

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM, TPHSMM, frame_poses, learn, learn_from_folder, load_demo_frames, load_demos, load_model, retrieve, save_model
from stl_lfd.hsmm.tp import relevant_frames
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable, write_signal_csv
from tests.conftest import ROOT

PICK = ROOT / "demos" / "pick"
INSERT = ROOT / "demos" / "insert"
RIGID = Pose((0.05, -0.12, 0.03), 0.4)  # a rigid motion of the whole world: turn, then shift


@pytest.fixture(scope="module")
def insert_model():
    return learn_from_folder(INSERT, 6)[0]


def moved(demo: SignalTable, motion: Pose) -> SignalTable:
    points = motion.to_base(np.column_stack([demo.columns[name] for name in "xyz"]))
    return SignalTable(demo.times, {name: points[:, index] for index, name in enumerate("xyz")}, demo.source)


@pytest.mark.slow
def test_a_single_base_frame_is_the_plain_hsmm():
    folder = ROOT / "demos" / "three_regions"
    plain, _ = learn_from_folder(folder, 6)
    framed, _ = learn_from_folder(folder, 6, frames=["base"])
    assert isinstance(framed, TPHSMM) and not isinstance(plain, TPHSMM)
    for name in ("means_", "covars_", "duration_means_", "duration_stds_", "transmat_", "startprob_"):
        assert np.array_equal(getattr(plain, name), getattr(framed, name)), name
    assert np.array_equal(retrieve(plain, rate=240).positions, retrieve(framed, rate=240).positions)


@pytest.mark.slow
def test_moving_demonstrations_and_frames_together_leaves_the_frame_model_and_moves_the_retrieval():
    demos = load_demos(INSERT)
    poses = load_demo_frames(demos)
    frames = ["shaft", "holder"]
    model, _ = learn(demos, 6, poses=poses, frames=frames)
    moved_poses = [{name: RIGID.compose(pose) for name, pose in demo_poses.items()} for demo_poses in poses]
    moved_model, _ = learn([moved(demo, RIGID) for demo in demos], 6, poses=moved_poses, frames=frames)
    assert np.allclose(model.means_, moved_model.means_, atol=1e-9)
    assert np.allclose(model.covars_, moved_model.covars_, atol=1e-12)
    assert np.allclose(model.duration_means_, moved_model.duration_means_)
    assert np.allclose(model.transmat_, moved_model.transmat_)
    new = {"shaft": Pose((0.41, -0.3, 0.08)), "holder": Pose((0.6, 0.15, 0.04), -0.3)}
    here = retrieve(model, rate=100, poses=new).positions
    there = retrieve(moved_model, rate=100, poses={name: RIGID.compose(pose) for name, pose in new.items()}).positions
    assert np.abs(RIGID.to_base(here) - there).max() < 1e-6


@pytest.mark.slow
def test_the_retrieved_pick_ends_at_the_shaft_wherever_it_stands():
    model, _ = learn_from_folder(PICK, 6)
    assert model.frame_names_ == ["base", "shaft"]
    for shaft in ((0.40, -0.21, 0.08), (0.50, -0.31, 0.08)):
        end = retrieve(model, poses={"shaft": Pose(shaft)}).positions[-1]
        assert np.linalg.norm(end - (np.array(shaft) + [0, 0, 0.03])) < 0.002  # the grasp pose, 3 cm above the centre


def test_the_insert_ends_over_the_hole_in_the_holders_frame(insert_model):
    for yaw in (-0.4, 0.0, 0.4):
        holder = Pose((0.57, 0.18, 0.04), yaw)
        end = retrieve(insert_model, poses={"shaft": Pose((0.45, -0.25, 0.08)), "holder": holder}).positions[-1]
        local = holder.from_base(end[None])[0]
        assert np.abs(local - [0.008, 0.0, 0.075]).max() < 0.004  # the demonstrated stop: 8 mm along the holder's x


def test_tp_model_files_keep_their_frames_and_old_files_load(insert_model, tmp_path):
    save_model(insert_model, tmp_path / "insert.npz")
    loaded = load_model(tmp_path / "insert.npz")
    assert isinstance(loaded, TPHSMM) and loaded.frame_names_ == insert_model.frame_names_
    assert np.array_equal(loaded.means_, insert_model.means_)
    plain = HSMM(2)
    arrays = {
        "means": np.zeros((2, 3)),
        "covars": np.array([np.eye(3)] * 2),
        "duration_means": np.ones(2),
        "duration_stds": np.ones(2),
        "transmat": np.eye(2, k=1),
        "startprob": np.eye(2)[0],
    }
    np.savez(tmp_path / "v1.npz", format="stlopt-hsmm", format_version=1, n_states=2, sample_period=0.02, signal_names=np.array(["x", "y", "z"]), **arrays)
    old = load_model(tmp_path / "v1.npz")
    assert type(old) is type(plain) and old.signal_names_ == ["x", "y", "z"]


def test_a_tp_model_needs_every_frame_pose(insert_model):
    with pytest.raises(ModelError, match="no pose for frame holder"):
        retrieve(insert_model, poses={"shaft": Pose((0.45, -0.25, 0.08))})
    with pytest.raises(ModelError, match="give the pose of holder"):
        frame_poses(insert_model, ["shaft=0.45,-0.25,0.08"], "insert.npz")
    with pytest.raises(ModelError, match="has no frame 'cup'"):
        frame_poses(insert_model, ["cup=0.45,-0.25,0.08"], "insert.npz")
    with pytest.raises(ConfigError, match="expected NAME=x,y,z"):
        frame_poses(insert_model, ["shaft=0.45,-0.25"], "insert.npz")


def copy_demos(source, target, count=3):
    target.mkdir()
    for demo in load_demos(source)[:count]:
        write_signal_csv(demo, target / (demo.source.rsplit("/", 1)[-1]))
    return target


def test_sidecar_problems_are_one_clear_error(tmp_path):
    folder = copy_demos(PICK, tmp_path / "pick")
    (folder / "demo_01.frames.yaml").write_text("frames:\n  shaft: {position: [0.4, -0.2, 0.08]}\n")
    with pytest.raises(ConfigError, match="demo_02.frames.yaml: missing; demo_01.frames.yaml gives frames"):
        learn_from_folder(folder, 4)
    (folder / "demo_02.frames.yaml").write_text("frames:\n  cup: {position: [0.4, -0.2, 0.08]}\n")
    (folder / "demo_03.frames.yaml").write_text("frames:\n  shaft: {position: [0.4, -0.2, 0.08]}\n")
    with pytest.raises(ConfigError, match=r"demo_02.frames.yaml: frames cup differ from demo_01.frames.yaml \(shaft\)"):
        learn_from_folder(folder, 4)
    (folder / "demo_02.frames.yaml").write_text("frames:\n  shaft: {position: [0.4, -0.2]}\n")
    with pytest.raises(ConfigError, match=r"demo_02.frames.yaml:2:11: 'frames.shaft.position' must be a list of 3 numbers"):
        learn_from_folder(folder, 4)
    (folder / "demo_02.frames.yaml").write_text("poses:\n  shaft: {position: [0.4, -0.2, 0.08]}\n")
    with pytest.raises(ConfigError, match="demo_02.frames.yaml:1:1: unknown key 'poses'"):
        learn_from_folder(folder, 4)
    (folder / "demo_02.frames.yaml").write_text("frames:\n  base: {position: [0.4, -0.2, 0.08]}\n")
    with pytest.raises(ConfigError, match="other than 'base'"):
        learn_from_folder(folder, 4)
    with pytest.raises(ModelError, match="no frame holder"):
        learn_from_folder(PICK, 4, frames=["shaft", "holder"])
    with pytest.raises(ModelError, match="no demonstration has a frame sidecar"):
        learn_from_folder(ROOT / "demos" / "three_regions", 4, frames=["shaft"])


def test_retrieval_ends_where_the_demonstrations_end_and_the_end_moves_with_the_final_state(learned_model):
    from stl_lfd.hsmm.demos import resample

    demos = load_demos(ROOT / "demos" / "three_regions")
    sequences = [resample(demo, learned_model.sample_period_) for demo in demos]
    mean_end = np.mean([sequence[-1] for sequence in sequences], axis=0)
    extent = np.ptp(np.concatenate(sequences), axis=0).max()
    end = retrieve(learned_model).positions[-1]
    assert np.linalg.norm(end - mean_end) < 0.02 * extent
    assert np.linalg.norm(learned_model.means_[-1] - mean_end) > 0.1 * extent  # the final state's mean is not the end
    moved = __import__("copy").deepcopy(learned_model)
    moved.means_ = moved.means_.copy()
    moved.means_[learned_model.end_state_] += [0.03, -0.02, 0.0]
    assert np.allclose(retrieve(moved).positions[-1], end + [0.03, -0.02, 0.0], atol=1e-3)


def test_models_without_an_end_point_retrieve_as_before(learned_model):
    import copy

    old = copy.deepcopy(learned_model)
    old.end_offsets_ = None
    trajectory = retrieve(old)
    assert np.linalg.norm(trajectory.positions[-1] - learned_model.means_[-1]) < 0.01


def unseen_placements(count: int = 20) -> list[dict[str, Pose]]:
    """Object poses the insert demonstrations never saw, from a generator seeded for this test
    alone: the first half inside the demonstrations' x-y range, the second half up to 3 cm
    beyond it; any holder yaw and any shaft yaw."""
    poses = load_demo_frames(load_demos(ROOT / "demos" / "insert"))
    rng = np.random.default_rng(20261203)
    placements = []
    for index in range(count):
        beyond = 0.03 if index >= count // 2 else 0.0
        drawn = {}
        for frame, height in (("holder", 0.04), ("shaft", 0.08)):
            xs, ys = [pose[frame].position[0] for pose in poses], [pose[frame].position[1] for pose in poses]
            position = (rng.uniform(min(xs) - beyond, max(xs) + beyond), rng.uniform(min(ys) - beyond, max(ys) + beyond), height)
            drawn[frame] = Pose(position, rng.uniform(-np.pi, np.pi))
        placements.append(drawn)
    return placements


def test_the_insert_ends_where_it_was_demonstrated_in_the_holders_frame_at_unseen_placements(insert_model):
    demos = load_demos(ROOT / "demos" / "insert")
    poses = load_demo_frames(demos)
    demonstrated = np.mean([pose["holder"].from_base(np.array([[demo.columns[n][-1] for n in "xyz"]]))[0] for demo, pose in zip(demos, poses)], axis=0)
    errors = [
        np.linalg.norm(placement["holder"].from_base(retrieve(insert_model, poses=placement).positions[-1:])[0] - demonstrated)
        for placement in unseen_placements()
    ]
    assert max(errors) < 0.002


def test_a_frame_far_less_certain_than_the_best_is_left_out_of_a_states_product():
    tight, loose, middle = np.eye(3) * 1e-6, np.eye(3) * 1e-3, np.eye(3) * 5e-6
    assert relevant_frames([tight, loose, middle], 10.0) == [0, 2]
    assert relevant_frames([tight, loose, middle], None) == [0, 1, 2]
