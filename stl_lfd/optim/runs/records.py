"""The records of a run directory's files: trials as JSON lines (`trials.jsonl`) and the
trials `stlopt ask` handed out and that are not recorded yet (`pending.json`)."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from stl_lfd.optim.trials import Trial


@dataclass(frozen=True)
class Pending:
    """A trial handed out by `stlopt ask` and not recorded yet (an entry of `pending.json`).

    Attributes:
        trial: its number (0: the unoptimised skill).
        phase: what chose it (`sobol`, `stl`, ...; `initial` for trial 0).
        x: its point (None for trial 0).
        optimizer_seconds: time spent choosing it.
        asked: when it was handed out (seconds since the epoch).
        robot: the name it was handed out to ("" when none was given).
        told: the trial as told, while it waits for the trials before it to be recorded (its
            signals are already in the run's signals/ folder); None until it is told.
        fingerprint: `handed_out_fingerprint` of its number, point and reference when it was
            handed out ("" in runs asked before fingerprints), checked when it is told.
    """

    trial: int
    phase: str
    x: np.ndarray | None
    optimizer_seconds: float
    asked: float
    robot: str = ""
    told: Trial | None = None
    fingerprint: str = ""

    def to_json(self) -> dict[str, Any]:
        data = {"trial": self.trial, "phase": self.phase, "x": None if self.x is None else [float(value) for value in self.x],
                "optimizer_seconds": self.optimizer_seconds, "asked": self.asked, "robot": self.robot}  # fmt: skip
        data |= {"fingerprint": self.fingerprint} if self.fingerprint else {}
        return data | ({"told": trial_to_json(self.told)} if self.told is not None else {})

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Pending":
        """An entry of pending.json; ValueError when a field is not what `ask` writes."""
        x = None if data["x"] is None else np.array(data["x"], dtype=float)
        if x is not None and (x.ndim != 1 or not np.all(np.isfinite(x))):
            raise ValueError(f"trial {data['trial']}'s point x is not a list of finite numbers")
        robot, fingerprint = data.get("robot", ""), data.get("fingerprint", "")
        if not isinstance(robot, str) or robot_name_problem(robot):
            raise ValueError(f"trial {data['trial']}'s robot is not a name")
        if not isinstance(fingerprint, str):
            raise ValueError(f"trial {data['trial']}'s fingerprint is not a string")
        told = trial_from_json(data["told"]) if data.get("told") is not None else None
        return cls(int(data["trial"]), str(data["phase"]), x, float(data["optimizer_seconds"]), float(data["asked"]), robot, told, fingerprint)

    @property
    def holder(self) -> str:
        """Who has it, for messages: `robot NAME`, or `the executor` for a nameless ask."""
        return f"robot {self.robot}" if self.robot else "the executor"


MAX_ROBOT_NAME = 64


def robot_name_problem(name: str) -> str:
    """What is wrong with a robot's name (printable characters, at most `MAX_ROBOT_NAME`), or ''."""
    if len(name) > MAX_ROBOT_NAME:
        return f"longer than {MAX_ROBOT_NAME} characters"
    if not name.isprintable():
        return "holds characters that are not printable (a newline, a tab, a terminal escape)"
    return ""


def handed_out_fingerprint(trial: int, x: np.ndarray | None, reference: bytes) -> str:
    """What identifies a handed-out trial: its number, its point (the exact doubles) and the
    bytes of its reference CSV."""
    digest = hashlib.sha256(f"{trial}\n".encode())
    digest.update(b"-" if x is None else np.ascontiguousarray(x, dtype="<f8").tobytes())
    digest.update(hashlib.sha256(reference).digest())
    return digest.hexdigest()


def finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def trial_problem(trial: Trial, expected_number: int) -> str:
    """What is wrong with a parsed trial record, or ''."""
    if trial.trial != expected_number:
        return f"trial {trial.trial} where trial {expected_number} was expected"
    if trial.status not in ("ok", "failed"):
        return f"status {trial.status!r}"
    if trial.robustness is not None and not math.isfinite(trial.robustness):
        return f"robustness {trial.robustness}"
    if (trial.robustness is None) != (trial.status == "failed"):
        return "a failed trial has a robustness, or a finished one has none"
    if trial.x.ndim != 1 or not np.all(np.isfinite(trial.x)):
        return "its point x is not a list of finite numbers"
    return ""


def trial_to_json(trial: Trial) -> dict[str, Any]:
    return {
        "trial": trial.trial,
        "phase": trial.phase,
        "robustness": trial.robustness,
        "satisfied": trial.satisfied,
        "status": trial.status,
        "error": trial.error,
        "wall_seconds": round(trial.wall_seconds, 4),
        "optimizer_seconds": round(trial.optimizer_seconds, 4),
        "rollout_seconds": round(trial.rollout_seconds, 4),
        "parameters": trial.parameters,
        "components": trial.components,
        **({"routes": trial.routes} if trial.routes else {}),
        "x": [float(value) for value in trial.x],
    }


def trial_from_json(data: dict[str, Any]) -> Trial:
    return Trial(
        trial=int(data["trial"]),
        phase=str(data["phase"]),
        x=np.array(data["x"], dtype=float),
        robustness=None if data["robustness"] is None else float(data["robustness"]),
        status=str(data["status"]),
        error=data.get("error"),
        optimizer_seconds=float(data.get("optimizer_seconds", 0.0)),
        rollout_seconds=float(data.get("rollout_seconds", 0.0)),
        parameters=dict(data.get("parameters", {})),
        components=None if data.get("components") is None else {str(k): float(v) for k, v in data["components"].items()},
        routes=None if data.get("routes") is None else {str(k): float(v) for k, v in data["routes"].items()},
    )
