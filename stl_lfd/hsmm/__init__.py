"""Skill models: HSMM and TP-HSMM learning from demonstrations, state sequences, LQT retrieval
(of one model, or of many variants of a skill together: `retrieve_batch`)."""

from stl_lfd.hsmm.demos import demonstration_sets, load_demo_frames, load_demos
from stl_lfd.hsmm.io import load_model, save_model
from stl_lfd.hsmm.learn import demonstrated_skill, frame_poses, learn, learn_from_folder, summary_rows
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.retrieval import Trajectory, retrieve, retrieve_batch
from stl_lfd.hsmm.tp import TPHSMM

__all__ = [
    "demonstration_sets",
    "HSMM",
    "TPHSMM",
    "Trajectory",
    "demonstrated_skill",
    "frame_poses",
    "learn",
    "learn_from_folder",
    "load_demo_frames",
    "load_demos",
    "load_model",
    "retrieve",
    "retrieve_batch",
    "save_model",
    "summary_rows",
]
