"""Skills learned from folders of demonstrations into model files, as `stlopt learn` learns
them: the skills a folder holds and where their models go (`skill_files`), then every skill
learned before any is written (`learn_skills`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from stl_lfd.errors import ConfigError
from stl_lfd.files import check_output_file, check_output_folder
from stl_lfd.hsmm.demos import demonstration_sets
from stl_lfd.hsmm.io import save_model
from stl_lfd.hsmm.learn import demonstrated_skill, learn_from_folder
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.spread import MinimumSpread
from stl_lfd.hsmm.states_choice import HeldOutScore, StatesChoice, choose_states
from stl_lfd.spelling import spelled

MODEL_FILE = Path("model.npz")  # where one skill's model goes by default
MODELS_FOLDER = Path("models")  # where the models of a folder of skills' folders go by default


@dataclass(frozen=True)
class SkillFiles:
    """One skill to learn: the folder (or CSV file) of its demonstrations, the model file to
    write, and its name when it is one skill of a folder of skills' folders ("" otherwise)."""

    demos: Path
    model: Path
    name: str = ""

    def figure(self, plot: Path | None) -> Path | None:
        """Where the skill's figure goes when one is asked for at `plot`: `plot` itself, or
        PLOT-NAME.png beside it for one skill of several."""
        if plot is None or not self.name:
            return plot
        return plot.with_name(f"{plot.stem}-{self.name}{plot.suffix}")


@dataclass(frozen=True)
class LearnedSkill:
    """A skill learned by `learn_skills`, not written yet.

    Attributes:
        files: where it is learned from and where its model goes.
        model: the learned `HSMM` (a `TPHSMM` from demonstrations with frame sidecars).
        sequences: the resampled demonstrations (`T_i x D` each, base frame).
        shown: the model as its demonstrations show it (`demonstrated_skill`: a TP-HSMM at the
            first demonstration's frame poses).
        states_choice: how K was chosen, when a range was given (None: K was given).
    """

    files: SkillFiles
    model: HSMM
    sequences: list[np.ndarray]
    shown: HSMM
    states_choice: StatesChoice | None = None

    def save(self) -> None:
        """Write the model file (creating the models folder of several skills)."""
        if self.files.name:
            self.files.model.parent.mkdir(parents=True, exist_ok=True)
        save_model(self.model, self.files.model)


def skill_files(demos: str | Path, output: str | Path | None = None) -> list[SkillFiles]:
    """The skills in `demos` and their model files, checked to be writable: the one skill of a
    folder of demonstration CSVs (or of one CSV) into `output` (default `MODEL_FILE`), or each
    skill of a folder of skills' folders (`demonstration_sets`) into `output/NAME.npz` (default
    `MODELS_FOLDER`)."""
    demos = Path(demos)
    sets = demonstration_sets(demos)
    if not sets:
        return [SkillFiles(demos, check_output_file(output if output is not None else MODEL_FILE, (".npz",), "model file"))]
    if output is not None and Path(output).suffix.lower() == ".npz":
        option, names = spelled("output"), ", ".join(path.name for path in sets)
        raise ConfigError(f"{option} {output}: {demos} holds one folder per skill ({names}); {option} names the folder their models go into")
    folder = check_output_folder(output if output is not None else MODELS_FOLDER, "models folder")
    return [SkillFiles(path, folder / f"{path.name}.npz", path.name) for path in sets]


def learn_skills(
    skills: list[SkillFiles],
    n_states: int | range = 6,
    sample_period: float | None = None,
    frames: list[str] | None = None,
    restarts: int = 1,
    min_spread: MinimumSpread | None | str = "auto",
    progress: Callable[[SkillFiles, int, HeldOutScore | None], None] | None = None,
) -> list[LearnedSkill]:
    """Learn every skill of `skills` (`learn_from_folder` with these settings), all of them
    before any is written: a skill that cannot be learned leaves no model file behind.

    A range of K chooses each skill's own K from it (`choose_states`), calling
    `progress(files, K, score)` after each K tried.
    """
    learned = []
    for files in skills:
        choice = None
        if isinstance(n_states, range):
            report = None if progress is None else lambda K, score, files=files: progress(files, K, score)
            choice = choose_states(files.demos, n_states, sample_period, frames, restarts, min_spread, report)
        model, sequences = learn_from_folder(files.demos, choice.chosen if choice else n_states, sample_period, frames, restarts, min_spread)
        learned.append(LearnedSkill(files, model, sequences, demonstrated_skill(model, files.demos), choice))
    return learned
