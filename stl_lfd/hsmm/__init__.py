"""Skill models: HSMM and TP-HSMM learning from demonstrations (one skill, or every skill of a
folder into its model file: `skill_files`, `learn_skills`), state sequences, LQT retrieval (of
one model, or of many variants of a skill together: `retrieve_batch`; of a model file:
`retrieve_file`)."""

from stl_lfd.hsmm.demos import demonstration_sets, load_demo_frames, load_demos
from stl_lfd.hsmm.io import load_model, save_model
from stl_lfd.hsmm.learn import demonstrated_skill, frame_poses, learn, learn_from_folder, summary_rows
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.retrieval import Trajectory, retrieve, retrieve_batch, retrieve_file
from stl_lfd.hsmm.skill_files import LearnedSkill, SkillFiles, learn_skills, skill_files
from stl_lfd.hsmm.tp import TPHSMM

__all__ = [
    "demonstration_sets",
    "HSMM",
    "LearnedSkill",
    "SkillFiles",
    "TPHSMM",
    "Trajectory",
    "demonstrated_skill",
    "frame_poses",
    "learn",
    "learn_from_folder",
    "learn_skills",
    "load_demo_frames",
    "load_demos",
    "load_model",
    "retrieve",
    "retrieve_batch",
    "retrieve_file",
    "save_model",
    "skill_files",
    "summary_rows",
]
