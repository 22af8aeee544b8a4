"""A corpus of bad inputs and faults, as a user meets them: each case runs one command and
asserts its exit code, one error line (spec errors add the source line and a caret), no
traceback, nothing on stdout, and that no input and no existing run changed.

Placeholders in the arguments: {case} (a fresh folder holding the case's `files`), {model} (a
learned model), {run} (a finished run; cases that damage a run get a copy at {case}/run),
{task} (a valid task file), {slow_model} (a model whose states last 10^9 s), {spec}, {csv},
{demos}.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import pytest
from typer.testing import CliRunner

from stl_lfd.cli import app
from tests.conftest import ROOT

runner = CliRunner()
TASK = (
    "spec: @spec@\nmodel: @model@\nbackend: kinematic\nduration: 22\nrate: 50\nparameters: {means: {components: [2, 3]}}\noptimizer: {initial: 2, trials: 3}\n"
)
PHI1 = str(ROOT / "specs" / "phi1.stl")
HOLE_SCENE = (
    "description: a peg and a hole\nobjects:\n"
    "  - {{name: peg, shape: cylinder, size: [0.01, 0.1], position: [0.4, 0, 0.05], mass: 0.05}}\n"
    "  - {{name: wall, shape: box, size: [0.01, 0.03, 0.02], position: [0.52, 0.2, 0.04]}}\n"
    "frames:\n  peg: {{position: [0.4, 0, 0.05], objects: [peg], into: hole}}\n"
    "  hole: {{position: [0.55, 0.2, 0.04], objects: [wall], rim: {rim}}}\n"
)


@dataclass
class Case:
    id: str
    arguments: list[str]
    code: int
    message: str
    files: dict[str, str | bytes] = field(default_factory=dict)
    damage: Callable[[Path], None] | None = None


def task_text(**changes: str) -> str:
    """A valid task file's text with top-level keys replaced (a value None drops the key)."""
    lines = dict(line.split(": ", 1) for line in TASK.strip().split("\n"))
    lines.update(changes)
    return "".join(f"{key}: {value}\n" for key, value in lines.items() if value is not None)


def spec_case(id: str, text: str, code: int, message: str, csv: str | None = None) -> Case:
    files = {"s.stl": text} | ({"s.csv": csv} if csv is not None else {})
    return Case(id, ["robustness", "{case}/s.stl", "{case}/s.csv" if csv is not None else str(ROOT / "examples" / "s1.csv")], code, message, files)


def csv_case(id: str, text: str | bytes, message: str) -> Case:
    return Case(id, ["robustness", "{case}/s.stl", "{case}/s.csv"], 4, message, {"s.stl": "phi := F s > 0\n", "s.csv": text})


def task_case(id: str, message: str, code: int = 5, extra: list[str] | None = None, **changes: str) -> Case:
    return Case(id, ["optimize", "{case}/t.yaml", "--out", "{case}/out"] + (extra or []), code, message, {"t.yaml": task_text(**changes)})


def _edit_json_line(number: int, **changes) -> Callable[[Path], None]:
    def damage(run: Path) -> None:
        lines = (run / "trials.jsonl").read_text().splitlines()
        record = json.loads(lines[number - 1])
        record.update(changes)
        lines[number - 1] = json.dumps(record)
        (run / "trials.jsonl").write_text("\n".join(lines) + "\n")

    return damage


ASKED_RUN: list[Path] = []  # the workspace's run with one more trial handed out (set by `workspace`)


def edit_pending(run: Path, **changes) -> None:
    """Make `run` the run with a trial handed out, then change fields of that trial in pending.json."""
    ask_one_more(run)
    data = json.loads((run / "pending.json").read_text())
    data["pending"][0].update(changes)
    (run / "pending.json").write_text(json.dumps(data))


def ask_one_more(run: Path) -> None:
    """Make `run` the finished run with one more trial handed out (a pending trial to tell)."""
    shutil.rmtree(run)
    shutil.copytree(ASKED_RUN[0], run)


def recording(times=None, **columns) -> str:
    """A recording of the workspace task (22 s at 50 samples/s) holding still in front of the
    robot, with `columns` (name -> function of the row index and time) replaced."""
    times = [index / 50 for index in range(1101)] if times is None else times
    values = {"x": lambda i, t: 0.5, "y": lambda i, t: 0.0, "z": lambda i, t: 0.4, "force": lambda i, t: 0.0} | columns
    rows = [",".join(["t"] + list(values))] + [",".join([repr(t)] + [repr(float(value(i, t))) for value in values.values()]) for i, t in enumerate(times)]
    return "\n".join(rows) + "\n"


def tell_case(id: str, text: str, message: str, code: int = 4) -> Case:
    return Case(id, ["tell", "{case}/run", "{case}/s.csv"], code, message, {"s.csv": text}, damage=ask_one_more)


DAMAGES: dict[str, tuple[Callable[[Path], None], str]] = {
    "empty-trials": (lambda run: (run / "trials.jsonl").write_text(""), "no successful trial yet"),
    "nan-robustness": (_edit_json_line(1, robustness=float("nan")), "damaged (robustness nan)"),
    "missing-signals": (lambda run: shutil.rmtree(run / "signals"), "signals/ folder is missing"),
    "trial-gap": (_edit_json_line(2, trial=7), "trial 7 where trial 2 was expected"),
    "garbage-line": (lambda run: (run / "trials.jsonl").write_text("{not json\n" + (run / "trials.jsonl").read_text()), "trials.jsonl:1: damaged"),
    "empty-summary": (lambda run: (run / "summary.json").write_text(""), "summary.json:1: not valid JSON"),
    "summary-list": (lambda run: (run / "summary.json").write_text("[]"), "no finite 'initial_robustness'"),
    "missing-task": (lambda run: (run / "task.yaml").unlink(), "no task.yaml"),
    "missing-model": (lambda run: (run / "model.npz").unlink(), "no model.npz"),
    "bad-status": (_edit_json_line(1, status="weird"), "status 'weird'"),
    "short-x": (_edit_json_line(1, x=[0.1]), "do not have the task's"),
    "inputs-garbage": (lambda run: (run / "inputs.json").write_text("{"), "inputs.json: damaged"),
}

CASES = [
    # --- specifications ---------------------------------------------------------------------
    Case("spec-missing", ["robustness", "{case}/nope.stl", "{csv}"], 3, "no such specification file"),
    Case("spec-is-folder", ["robustness", "{case}", "{csv}"], 3, "is a folder, not a specification file"),
    spec_case("spec-empty", "", 3, "the specification is empty"),
    spec_case(
        "spec-nested-3000", "phi := " + "G[0, 1] " * 3000 + "s > 0\n", 3, "the specification nests more than 200 levels deep (counting through its definitions)"
    ),
    spec_case("spec-chained-implications", "phi := " + " -> ".join(["s > 0"] * 5000) + "\n", 3, "nests more than 200 levels deep"),
    spec_case("spec-only-comment", "# nothing\n", 3, "the specification is empty"),
    spec_case("spec-unbalanced", "phi := F (s > 0\n", 3, "s.stl:1:16: unexpected end of input"),
    spec_case("spec-bad-token", "phi := F s >> 0\n", 3, "s.stl:1"),
    spec_case("spec-unknown-signal", "phi := F q > 0\n", 3, "unknown signal 'q'"),
    spec_case("spec-undefined-name", "phi := F B\n", 3, "undefined formula 'B'"),
    spec_case("spec-recursive", "A := F B\nB := G A\n", 3, "recursive definition"),
    spec_case("spec-defined-twice", "A := s > 0\nA := s < 1\nphi := F A\n", 3, "'A' is defined twice"),
    spec_case("spec-empty-interval", "phi := F[5, 2] s > 0\n", 3, "empty interval [5, 2]"),
    spec_case("spec-negative-interval", "phi := G[-1, 2] s > 0\n", 3, "interval bounds must be non-negative"),
    spec_case("spec-huge-bound", "phi := F[0, 1e400] s > 0\n", 3, "the number 1e400 is too large"),
    spec_case("spec-huge-constant", "phi := F s > 1e999\n", 3, "the number 1e999 is too large"),
    spec_case("spec-divide-by-zero", "phi := G s / 0 > 1\n", 3, "is infinite at t = 0 s"),
    spec_case("spec-zero-over-zero", "phi := G (s - s) / (s - s) > 0\n", 3, "is NaN at t = 0 s"),
    spec_case("spec-overflow", "phi := F s * 1e308 * 1e308 > 0\n", 3, "is infinite"),
    spec_case("spec-deep-negation", "phi := " + "!" * 350 + " s > 0\n", 3, "nests more than 200 levels"),
    spec_case("spec-deep-parentheses", "phi := " + "G (" * 400 + "s > 0" + ")" * 400 + "\n", 3, "nests more than 200 levels"),
    spec_case("spec-deep-definitions", "A0 := s > 0\n" + "".join(f"A{i} := F A{i - 1}\n" for i in range(1, 260)), 3, "nests more than 200 levels"),
    spec_case("spec-formula-in-arithmetic", "A := s > 0\nphi := A + 1 > 0\n", 3, "is a formula, not a signal"),
    spec_case("spec-include-missing", 'include "nope.stl"\nphi := s > 0\n', 3, "included file 'nope.stl' does not exist"),
    spec_case("spec-include-folder", 'include "/tmp"\nphi := s > 0\n', 3, "is a folder, not a specification file"),
    spec_case("spec-include-self", 'include "s.stl"\nphi := s > 0\n', 3, "circular include"),
    spec_case("spec-binary", "\x00\x01\xff", 3, "s.stl"),
    Case("spec-not-utf8", ["robustness", "{case}/s.stl", "{csv}"], 3, "not a text file", {"s.stl": b"phi := s > \xff\n"}),
    Case("nu-zero", ["robustness", PHI1, "{csv}", "--semantics", "new", "--nu", "0"], 3, "nu"),
    Case("nu-negative", ["robustness", PHI1, "{csv}", "--semantics", "new", "--nu", "-1"], 3, "nu"),
    Case("nu-nan", ["robustness", PHI1, "{csv}", "--semantics", "new", "--nu", "nan"], 3, "nu"),
    Case("semantics-unknown", ["robustness", PHI1, "{csv}", "--semantics", "fuzzy"], 2, "fuzzy"),
    # --- signal files -----------------------------------------------------------------------
    Case("csv-missing", ["robustness", PHI1, "{case}/nope.csv"], 4, "no such CSV file"),
    Case("csv-is-folder", ["robustness", PHI1, "{case}"], 4, "is a folder"),
    csv_case("csv-empty", "", "the file is empty"),
    csv_case("csv-header-only", "t,s\n", "has a header but no samples"),
    csv_case("csv-no-time", "s\n1\n2\n", "missing column 't'"),
    csv_case("csv-bom-no-time", "\ufeffs,u\n1,2\n", "missing column 't' (the header has: s, u)"),
    Case(
        "csv-missing-signal",
        ["robustness", "{case}/s.stl", "{case}/s.csv"],
        3,
        "unknown signal 's' (the trace has: u)",
        {"s.stl": "phi := F s > 0\n", "s.csv": "t,u\n0,1\n1,2\n"},
    ),
    csv_case("csv-text-cell", "t,s\n0,1\n1,abc\n", "s.csv:3: column 's' has 'abc'"),
    csv_case("csv-nan-cell", "t,s\n0,1\n1,nan\n", "s.csv:3: column 's' is nan"),
    csv_case("csv-inf-cell", "t,s\n0,inf\n1,1\n", "s.csv:2: column 's' is inf"),
    csv_case("csv-short-row", "t,s\n0,1\n1\n", "s.csv:3: expected 2 values, found 1"),
    csv_case("csv-time-backwards", "t,s\n0,1\n2,1\n1,1\n", "time must be strictly increasing"),
    csv_case("csv-time-repeated", "t,s\n0,1\n0,1\n", "time must be strictly increasing"),
    csv_case("csv-non-uniform", "t,s\n0,1\n1,1\n3,1\n", "s.csv: sample times are not uniform"),
    csv_case("csv-duplicate-column", "t,s,s\n0,1,1\n", "duplicate column 's'"),
    csv_case("csv-empty-column-name", "t,,s\n0,1,1\n", "empty column name"),
    csv_case("csv-binary", b"\x89PNG\r\n\x1a\n\x00\x00", "not a text file"),
    # --- learning ---------------------------------------------------------------------------
    Case("learn-missing-folder", ["learn", "{case}/nope", "-o", "{case}/m.npz"], 4, "no such folder of demonstrations"),
    Case("learn-empty-folder", ["learn", "{case}", "-o", "{case}/m.npz"], 4, "no demonstration CSV files"),
    Case("learn-k-zero", ["learn", "{demos}", "-K", "0", "-o", "{case}/m.npz"], 6, "K must be from 1 to 200"),
    Case("learn-k-huge", ["learn", "{demos}", "-K", "100000", "-o", "{case}/m.npz"], 6, "K must be from 1 to 200"),
    Case(
        "learn-k-too-many-for-demos",
        ["learn", "{case}", "-K", "3", "-o", "{case}/m.npz"],
        6,
        "use a smaller K",
        {"d.csv": "t,x,y,z\n0,1,1,1\n1,1,1,2\n2,1,1,3\n"},
    ),
    Case("learn-frames-unknown", ["learn", "{demos}", "--frames", "cup", "-o", "{case}/m.npz"], 6, "no frame cup (no demonstration has a frame sidecar"),
    Case("retrieve-frame-unknown", ["retrieve", "{model}", "--frame", "shaft=0.4,-0.2,0.08"], 6, "has no frame 'shaft' (it was learned without frames)"),
    Case("retrieve-frame-malformed", ["retrieve", "{model}", "--frame", "shaft=0.4"], 5, "expected NAME=x,y,z[,yaw]"),
    Case(
        "rollout-place-off-table",
        ["rollout", str(ROOT / "configs" / "behaviours" / "pick_insert.yaml"), "--place", "holder=0.9,0.2"],
        5,
        "outside the area it may be placed in",
    ),
    Case("rollout-place-unknown", ["rollout", "{model}", "--backend", "kinematic", "--place", "cup=0.5,0.2"], 5, "no frame 'cup' (frames: none)"),
    Case("learn-period-zero", ["learn", "{demos}", "--sample-period", "0", "-o", "{case}/m.npz"], 6, "the sample period must be a positive"),
    Case("learn-period-negative", ["learn", "{demos}", "--sample-period", "-1", "-o", "{case}/m.npz"], 6, "the sample period must be a positive"),
    Case("learn-period-nan", ["learn", "{demos}", "--sample-period", "nan", "-o", "{case}/m.npz"], 6, "the sample period must be a positive"),
    Case("learn-period-tiny", ["learn", "{demos}", "--sample-period", "1e-6", "-o", "{case}/m.npz"], 6, "above the limit"),
    Case("learn-output-folder", ["learn", "{demos}", "-o", "{case}"], 8, "is a folder; give a file name"),
    Case("learn-output-missing-folder", ["learn", "{demos}", "-o", "{case}/nope/m.npz"], 8, "does not exist"),
    Case("learn-output-under-file", ["learn", "{demos}", "-o", "{case}/f.txt/m.npz"], 8, "is a file", {"f.txt": "x"}),
    Case("learn-output-suffix", ["learn", "{demos}", "-o", "{case}/m.txt"], 8, "must end in .npz"),
    Case("learn-plot-suffix", ["learn", "{demos}", "-o", "{case}/m.npz", "--plot", "{case}/x.txt"], 8, "must end in .png, .pdf or .svg"),
    Case("learn-plot-missing-folder", ["learn", "{demos}", "-o", "{case}/m.npz", "--plot", "{case}/no/x.png"], 8, "does not exist"),
    Case("learn-demo-no-x", ["learn", "{case}", "-o", "{case}/m.npz"], 4, "missing column 'x'", {"d.csv": "t,y,z\n0,1,1\n1,1,1\n"}),
    Case("learn-demo-one-sample", ["learn", "{case}", "-o", "{case}/m.npz"], 4, "needs at least 2 samples", {"d.csv": "t,x,y,z\n0,1,1,1\n"}),
    Case(
        "learn-demos-differ",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        4,
        "differ from",
        {"a.csv": "t,x,y,z\n0,1,1,1\n1,1,1,1\n", "b.csv": "t,x,y,z,g\n0,1,1,1,0\n1,1,1,1,0\n"},
    ),
    Case(
        "learn-quaternion-nan",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        4,
        "d.csv:3: column 'qw' is nan",
        {"d.csv": "t,x,y,z,qx,qy,qz,qw\n0,1,1,1,1,0,0,0\n1,1,1,1,1,0,0,nan\n"},
    ),
    Case(
        "learn-quaternion-not-unit",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        4,
        "d.csv:2: qx,qy,qz,qw = 2,0,0,0 is not a unit quaternion (norm 2",
        {"d.csv": "t,x,y,z,qx,qy,qz,qw\n0,1,1,1,2,0,0,0\n1,1,1,1,2,0,0,0\n"},
    ),
    Case(
        "learn-quaternion-partial",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        4,
        "the orientation needs all of qx, qy, qz, qw (no column qw)",
        {"d.csv": "t,x,y,z,qx,qy,qz\n0,1,1,1,1,0,0\n1,1,1,1,1,0,0\n"},
    ),
    Case(
        "learn-sidecar-orientation-not-unit",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        5,
        "'frames.cup.orientation' must be a unit quaternion [qx, qy, qz, qw] (its norm is 0.5)",
        {"d.csv": "t,x,y,z\n0,1,1,1\n1,1,1,1\n", "d.frames.yaml": "frames: {cup: {position: [0.5, 0, 0], orientation: [0.5, 0, 0, 0]}}\n"},
    ),
    Case(
        "learn-sidecar-orientation-and-yaw",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        5,
        "'frames.cup' gives both 'yaw' and 'orientation'; give one",
        {"d.csv": "t,x,y,z\n0,1,1,1\n1,1,1,1\n", "d.frames.yaml": "frames: {cup: {position: [0.5, 0, 0], yaw: 1, orientation: [0, 0, 0, 1]}}\n"},
    ),
    Case(
        "learn-sidecar-orientation-short",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        5,
        "'frames.cup.orientation' must be a list of 4 numbers",
        {"d.csv": "t,x,y,z\n0,1,1,1\n1,1,1,1\n", "d.frames.yaml": "frames: {cup: {position: [0.5, 0, 0], orientation: [0, 0, 1]}}\n"},
    ),
    # --- models and retrieval ---------------------------------------------------------------
    Case("model-missing", ["retrieve", "{case}/nope.npz"], 6, "no such model file"),
    Case("model-empty", ["retrieve", "{case}/m.npz"], 6, "not a model file (it is empty)", {"m.npz": b""}),
    Case("model-text", ["retrieve", "{case}/m.npz"], 6, "not a model file (not an .npz archive)", {"m.npz": "hello\n"}),
    Case("model-folder", ["retrieve", "{case}"], 6, "is a folder, not a model file"),
    Case("retrieve-model-durations-huge", ["retrieve", "{slow_model}"], 6, "slow.npz (its expected duration, 6e+09 s): cannot retrieve the skill"),
    Case("rollout-model-durations-huge", ["rollout", "{slow_model}", "--backend", "kinematic"], 6, "above the limit of 2,000,000"),
    Case("retrieve-duration-zero", ["retrieve", "{model}", "--duration", "0"], 6, "the duration must be a positive"),
    Case("retrieve-duration-negative", ["retrieve", "{model}", "--duration", "-3"], 6, "the duration must be a positive"),
    Case("retrieve-duration-inf", ["retrieve", "{model}", "--duration", "inf"], 6, "the duration must be a positive"),
    Case("retrieve-duration-nan", ["retrieve", "{model}", "--duration", "nan"], 6, "the duration must be a positive"),
    Case("retrieve-duration-huge", ["retrieve", "{model}", "--duration", "1e7"], 6, "above the limit of 2,000,000"),
    Case("retrieve-rate-zero", ["retrieve", "{model}", "--rate", "0"], 6, "the rate must be a positive"),
    Case("retrieve-rate-huge", ["retrieve", "{model}", "--rate", "1e7"], 6, "above the limit of 10000"),
    Case("retrieve-output-folder", ["retrieve", "{model}", "-o", "{case}"], 8, "is a folder"),
    Case("retrieve-output-missing-folder", ["retrieve", "{model}", "-o", "{case}/no/x.csv"], 8, "does not exist"),
    Case("retrieve-output-suffix", ["retrieve", "{model}", "-o", "{case}/x.npz"], 8, "must end in .csv"),
    # --- rollouts ---------------------------------------------------------------------------
    Case("rollout-unknown-scene", ["rollout", "{model}", "--scene", "kitchen"], 5, "unknown scene 'kitchen'"),
    Case("rollout-scene-missing-file", ["rollout", "{model}", "--scene", "{case}/s.yaml"], 5, "scene file not found"),
    Case("rollout-scene-bad-yaml", ["rollout", "{model}", "--scene", "{case}/s.yaml"], 5, "invalid YAML", {"s.yaml": "a: [1, 2\n"}),
    Case(
        "rollout-scene-unknown-key", ["rollout", "{model}", "--scene", "{case}/s.yaml"], 5, "unknown key 'colour'", {"s.yaml": "description: x\ncolour: red\n"}
    ),
    Case(
        "rollout-scene-duplicate-key",
        ["rollout", "{model}", "--scene", "{case}/s.yaml"],
        5,
        "duplicate key 'description'",
        {"s.yaml": "description: x\ndescription: y\n"},
    ),
    Case("rollout-backend-unknown", ["rollout", "{model}", "--backend", "gazebo"], 2, "gazebo"),
    Case("rollout-duration-huge", ["rollout", "{model}", "--backend", "kinematic", "--duration", "1e6"], 6, "above the limit"),
    Case("rollout-rate-zero", ["rollout", "{model}", "--rate", "0"], 6, "the rate must be a positive"),
    Case("rollout-output-folder", ["rollout", "{model}", "-o", "{case}"], 8, "is a folder"),
    Case("rollout-output-suffix", ["rollout", "{model}", "-o", "{case}/x.txt"], 8, "must end in .csv"),
    # --- files that are not what they claim: devices, huge, binary -----------------------------
    Case("spec-device", ["robustness", "/dev/zero", "{csv}"], 3, "not a regular file"),
    Case("spec-huge", ["robustness", "{case}/s.stl", "{csv}"], 3, "larger than 1 MB", {"s.stl": "phi := F x > 0\n" + "#" * 1_100_000 + "\n"}),
    Case("spec-nul-bytes", ["robustness", "{case}/s.stl", "{csv}"], 3, "holds NUL bytes", {"s.stl": b"phi := F x\x00\x00 > 0\n"}),
    Case("signals-device", ["robustness", "{spec}", "/dev/zero"], 4, "not a regular file"),
    Case("task-device", ["optimize", "/dev/zero", "--out", "{case}/out"], 5, "not a regular file"),
    # --- task files -------------------------------------------------------------------------
    Case("task-missing", ["optimize", "{case}/nope.yaml", "--out", "{case}/out"], 5, "no such YAML file"),
    Case("task-folder", ["optimize", "{case}", "--out", "{case}/out"], 5, "is a folder"),
    Case("task-bad-yaml", ["optimize", "{case}/t.yaml", "--out", "{case}/out"], 5, "t.yaml:2", {"t.yaml": "spec: a\n  - b: [\n"}),
    Case("task-not-mapping", ["optimize", "{case}/t.yaml", "--out", "{case}/out"], 5, "expected a mapping", {"t.yaml": "- 1\n- 2\n"}),
    Case("task-duplicate-key", ["optimize", "{case}/t.yaml", "--out", "{case}/out"], 5, "duplicate key 'duration'", {"t.yaml": task_text() + "duration: 5\n"}),
    Case(
        "task-alias-bomb",
        ["optimize", "{case}/t.yaml", "--out", "{case}/out"],
        5,
        "aliases expand to more than",
        {
            "t.yaml": "a: &a [1,1,1,1,1,1,1,1,1,1]\n"
            + "".join(f"{chr(98 + i)}: &{chr(98 + i)} [" + ",".join([f"*{chr(97 + i)}"] * 10) + "]\n" for i in range(6))
        },
    ),
    Case("task-huge-file", ["optimize", "{case}/t.yaml", "--out", "{case}/out"], 5, "larger than 1 MB", {"t.yaml": "# " + "x" * 1_100_000 + "\n"}),
    task_case("task-unknown-key", "unknown key 'iterations'", iterations="5"),
    task_case("task-no-spec", "missing key 'spec'", spec=None),
    task_case("task-spec-missing-file", "'spec' names nope.stl, which does not exist", spec="nope.stl"),
    task_case("task-model-and-demos", "give exactly one of 'model'", demos=str(ROOT / "demos" / "three_regions")),
    task_case("task-duration-text", "'duration' must be a number (got 'long')", duration="long"),
    task_case("task-duration-zero", "'duration' must be positive", duration="0"),
    task_case("task-rate-huge", "above the limit of 10000", rate="1e9"),
    task_case("task-rate-samples", "above the limit of 2,000,000", rate="1000", duration="1e4"),
    task_case("task-nu-negative", "'nu' must be positive", nu="-1"),
    task_case("task-semantics", "'semantics' must be one of classic, new", semantics="fuzzy"),
    task_case("task-backend", "'backend' must be one of pybullet, mujoco, kinematic", backend="gazebo"),
    task_case("task-name-slash", "'name' must be a plain name", name="../elsewhere"),
    task_case("task-seed-huge", "'optimizer.seed' must be at most 4294967295", optimizer="{seed: 1e23}"),
    task_case("task-seed-negative", "'optimizer.seed' must be at least 0", optimizer="{seed: -1}"),
    task_case("task-seed-text", "'optimizer.seed' must be an integer", optimizer="{seed: abc}"),
    task_case("task-trials-zero", "must be at least 1", optimizer="{trials: 0}"),
    task_case("task-trials-huge", "above the limit of 10000 trials", optimizer="{trials: 1e6}"),
    task_case("task-initial-above-trials", "exceeds 'optimizer.trials'", optimizer="{initial: 10, trials: 5}"),
    task_case("task-method", "'optimizer.method' must be one of", optimizer="{method: magic}"),
    task_case("task-optimizer-unknown-key", "unknown key 'optimizer.budget'", optimizer="{budget: 3}"),
    task_case("task-nothing-to-optimise", "selects nothing to optimise", parameters="{}"),
    task_case("task-state-out-of-range", "state 9", parameters="{means: {components: [9]}}"),
    task_case("task-state-twice", "lists a state twice", parameters="{means: {components: [2, 2]}}"),
    task_case("task-coordinate", "may hold x, y, z, rx, ry, rz (got 'w')", parameters="{means: {components: [2], coordinates: [w]}}"),
    task_case("task-beta-negative", "'parameters.means.beta' must be positive", parameters="{means: {components: [2], beta: -1}}"),
    task_case("task-transitions", "'parameters.transitions' must be one of none, band, full", parameters="{transitions: diag}"),
    task_case("task-horizon", "looks 17 s ahead but rollouts last 5 s", duration="5"),
    Case(
        "task-spec-unknown-signal",
        ["optimize", "{case}/t.yaml", "--out", "{case}/out"],
        3,
        "signal q is not recorded",
        {"t.yaml": task_text(spec="q.stl"), "q.stl": "phi := F q > 0\n"},
    ),
    task_case("cli-seed-huge", "must be from 0 to 4294967295", extra=["--seed", "99999999999999"]),
    task_case("cli-init-above-iterations", "error: --init 9 exceeds --iterations 4, the total", extra=["--init", "9", "--iterations", "4"]),
    task_case("cli-iterations-zero", "must be at least 1", extra=["--iterations", "0"]),
    task_case("cli-spec-missing", "no such specification file", code=3, extra=["--spec", "{case}/nope.stl"]),
    task_case("cli-method-unknown", "magic", code=2, extra=["--method", "magic"]),
    Case("out-under-file", ["optimize", "{task}", "--out", "{case}/f.txt/run"], 8, "is a file", {"f.txt": "x"}),
    Case("out-is-file", ["optimize", "{task}", "--out", "{case}/f.txt"], 9, "f.txt: is a file, not a run directory", {"f.txt": "x"}),
    Case("out-is-existing-run", ["optimize", "{task}", "--out", "{run}"], 9, "the run directory exists; continue it with --resume"),
    # --- resuming ---------------------------------------------------------------------------
    Case("resume-missing", ["optimize", "{task}", "--out", "{case}/nope", "--resume"], 9, "no such run directory"),
    Case("resume-not-a-run", ["optimize", "{task}", "--out", "{case}", "--resume"], 9, "not a run directory of stlopt optimize"),
    Case(
        "resume-other-seed", ["optimize", "{task}", "--out", "{run}", "--resume", "--seed", "5"], 9, "--seed cannot change on --resume (the run has 0, got 5)"
    ),
    Case(
        "resume-other-method",
        ["optimize", "{task}", "--out", "{run}", "--resume", "--method", "pi"],
        9,
        "--method cannot change on --resume (the run has plan, got pi)",
    ),
    Case("resume-other-backend", ["optimize", "{task}", "--out", "{run}", "--resume", "--backend", "pybullet"], 9, "--backend cannot change on --resume"),
    Case("resume-other-init", ["optimize", "{task}", "--out", "{run}", "--resume", "--init", "1"], 9, "--init cannot change on --resume"),
    Case(
        "resume-other-spec",
        ["optimize", "{task}", "--out", "{run}", "--resume", "--spec", str(ROOT / "specs" / "phi2.stl")],
        9,
        "--spec cannot change on --resume",
    ),
    Case(
        "resume-other-task",
        ["optimize", "{case}/t.yaml", "--out", "{run}", "--resume"],
        9,
        "not the task of the run",
        {"t.yaml": task_text(parameters="{means: {components: [2, 3]}, transitions: band}")},
    ),
    *[
        Case(f"damaged-resume-{name}", ["optimize", "{task}", "--out", "{case}/run", "--resume"], 9, message, damage=damage)
        for name, (damage, message) in DAMAGES.items()
        if name not in ("empty-trials",)
    ],
    *[
        Case(f"damaged-report-{name}", ["report", "{case}/run", "--out", "{case}/report"], 9, message, damage=damage)
        for name, (damage, message) in DAMAGES.items()
        if name not in ("empty-trials", "short-x", "inputs-garbage")
    ],
    Case(
        "damaged-resume-one-signal-file",
        ["optimize", "{task}", "--out", "{case}/run", "--resume", "-N", "5"],
        9,
        "the recorded signals of finished trials are missing (signals/trial-0002.csv); the run cannot go on without them",
        damage=lambda run: (run / "signals" / "trial-0002.csv").unlink(),
    ),
    Case("damaged-replay-empty-trials", ["replay", "{case}/run", "--video", "{case}/v.mp4"], 9, "no successful trial yet", damage=DAMAGES["empty-trials"][0]),
    # --- replay and report ------------------------------------------------------------------
    Case("replay-trial-negative", ["replay", "{run}", "--trial", "-1", "--video", "{case}/v.mp4"], 9, "no trial -1 (the run has trials 1 to 3"),
    Case("replay-trial-zero", ["replay", "{run}", "--trial", "0", "--video", "{case}/v.mp4"], 9, "no trial 0"),
    Case("replay-trial-beyond", ["replay", "{run}", "--trial", "99", "--video", "{case}/v.mp4"], 9, "no trial 99"),
    Case("replay-trial-word", ["replay", "{run}", "--trial", "last", "--video", "{case}/v.mp4"], 5, "--trial must be 'best', 'initial' or a trial number"),
    Case("replay-trial-on-model", ["replay", "{model}", "--trial", "3", "--video", "{case}/v.mp4"], 7, "--trial applies to run directories"),
    Case("replay-missing-source", ["replay", "{case}/nope", "--video", "{case}/v.mp4"], 5, "no such model file, behaviour file or run directory"),
    Case("replay-video-suffix", ["replay", "{model}", "--video", "{case}/v.avi"], 8, "must end in .mp4 or .gif"),
    Case("replay-video-folder", ["replay", "{model}", "--video", "{case}"], 8, "is a folder"),
    Case("replay-video-missing-folder", ["replay", "{model}", "--video", "{case}/no/v.mp4"], 8, "does not exist"),
    Case("replay-gui-without-display", ["replay", "{model}", "--gui"], 7, "--gui needs a display"),
    Case("report-missing-run", ["report", "{case}/nope"], 9, "no such run directory"),
    Case("report-not-a-run", ["report", "{case}"], 9, "not a run directory"),
    Case("report-out-is-file", ["report", "{run}", "--out", "{case}/f.txt"], 8, "is a file; the report folder must be a folder", {"f.txt": "x"}),
    Case("report-compare-missing", ["report", "{run}", "--out", "{case}/r", "--compare", "{case}/nope"], 9, "no such run directory"),
    Case("report-gp-parameter", ["report", "{run}", "--out", "{case}/r", "--gp-parameter", "mean[9].q"], 5, "is not a parameter of the run"),
    # External executors, the safety gate, ask and tell
    task_case("task-command-missing", "the command backend needs the command that executes a trial", backend="command"),
    task_case("task-command-bad-key", "unknown key 'command.program'", backend="command", command="{program: x}"),
    task_case("task-command-timeout", "'command.timeout' must be positive", backend="command", command="{run: x, timeout: 0}"),
    task_case("task-command-quote", "cannot be split into arguments (No closing quotation)", backend="command", command='"run \'x"'),
    task_case("task-command-shell-list", "a shell command must be one string", backend="command", command="{run: [a, b], shell: true}"),
    task_case("task-command-empty", "the command is empty", backend="command", command="{run: ''}"),
    task_case("optimize-command-other-backend", "--command is for --backend command", extra=["--command", "x"]),
    task_case("optimize-command-timeout-alone", "--command-timeout needs a command", extra=["--command-timeout", "5"]),
    Case("rollout-command-missing", ["rollout", "{model}", "--backend", "command"], 5, "the command backend needs a command"),
    Case("rollout-command-other-backend", ["rollout", "{model}", "--command", "x"], 5, "--command is for --backend command"),
    Case(
        "rollout-command-not-found",
        ["rollout", "{model}", "--backend", "command", "--command", "no-such-program-xyz {{reference}}"],
        7,
        "cannot start the command 'no-such-program-xyz' (No such file or directory)",
    ),
    Case(
        "rollout-command-no-safety",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "command", "--command", "x"],
        7,
        "the scene s declares no 'safety'",
        {"s.yaml": "description: bare\n"},
    ),
    Case(
        "rollout-command-unsafe",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "command", "--command", "x"],
        7,
        "unsafe reference, not executed: at t = 0.000 s it reaches",
        {"s.yaml": "description: x\nsafety: {workspace: {lower: [0, 0, 0], upper: [0.1, 0.1, 0.1]}, max_speed: 1}\n"},
    ),
    Case(
        "scene-safety-inverted",
        ["rollout", "{model}", "--scene", "{case}/s.yaml"],
        5,
        "'safety': the workspace's lower corner [0.5, 0.0, 0.0] must be below",
        {"s.yaml": "description: x\nsafety: {workspace: {lower: [0.5, 0, 0], upper: [0.4, 1, 1]}, max_speed: 1}\n"},
    ),
    Case(
        "scene-safety-no-speed",
        ["rollout", "{model}", "--scene", "{case}/s.yaml"],
        5,
        "missing key 'safety.max_speed'",
        {"s.yaml": "description: x\nsafety: {workspace: {lower: [0, 0, 0], upper: [1, 1, 1]}}\n"},
    ),
    Case("tell-nothing-pending", ["tell", "{run}", "{csv}"], 9, "no trial is pending; hand out the next one with: stlopt ask"),
    Case("tell-no-signals", ["tell", "{run}"], 2, "give the signals CSV of the pending trial, --failed REASON or --abandon"),
    Case("tell-missing-run", ["tell", "{case}/nope", "{csv}"], 9, "no such run directory"),
    Case(
        "tell-point-edited",
        ["tell", "{case}/run", "{csv}"],
        9,
        "trial 4's point (pending.json) or reference",
        damage=lambda run: edit_pending(run, x=[0.5, 0.5]),
    ),
    Case(
        "tell-point-one-number",
        ["tell", "{case}/run", "{csv}"],
        9,
        "trial 4's point x is not a list of finite numbers",
        damage=lambda run: edit_pending(run, x=5),
    ),
    Case(
        "tell-robot-escape-in-file",
        ["tell", "{case}/run", "{csv}"],
        9,
        "trial 4's robot is not a name",
        damage=lambda run: edit_pending(run, robot="\x1b[31mred"),
    ),
    Case(
        "tell-reference-edited",
        ["tell", "{case}/run", "{csv}"],
        9,
        "changed since it was handed out",
        damage=lambda run: (ask_one_more(run), open(run / "executions" / "trial-0004" / "reference.csv", "a").write("99,0,0,0,0,,,\n")),
    ),  # fmt: skip
    Case(
        "tell-pending-deep",
        ["tell", "{case}/run", "{csv}"],
        9,
        "pending.json: damaged (it nests too deeply)",
        damage=lambda run: (run / "pending.json").write_text("[" * 50_000),
    ),
    Case("ask-robot-newline", ["ask", "{run}", "--robot", "left\narm"], 5, "not printable"),
    Case("ask-robot-escape", ["ask", "{run}", "--robot", "\x1b[31mred"], 5, "not printable"),
    Case("ask-robot-long", ["ask", "{run}", "--robot", "r" * 100], 5, "longer than 64 characters"),
    Case("ask-run-with-seed", ["ask", "{run}", "--seed", "3"], 5, "a run directory keeps its own settings"),
    Case("ask-not-a-run", ["ask", "{case}"], 9, "not a run directory of stlopt optimize"),
    Case("ask-damaged-design", ["ask", "{case}/run"], 9, "design.json: damaged", damage=lambda run: (run / "design.json").write_text("[[0.1,")),
    Case("ask-task-missing", ["ask", "{case}/nope.yaml", "--out", "{case}/out"], 5, "no such YAML file"),
    # --- what comes back from a robot (stlopt tell): implausible recordings ---------------------
    tell_case("tell-absurd-everywhere", recording(x=lambda i, t: 1e300), "s.csv:2: the hand at (x=1e+300"),
    tell_case("tell-absurd-one-sample", recording(z=lambda i, t: 1e308 if i == 40 else 0.4), "s.csv:42: the hand at (x=0.5, y=0, z=1e+308)"),
    tell_case("tell-a-metre-off", recording(y=lambda i, t: 1.5), "more than 0.25 m outside the scene's workspace"),
    tell_case("tell-below-the-floor", recording(z=lambda i, t: -0.5), "s.csv:2: the hand at (x=0.5, y=0, z=-0.5)"),
    tell_case(
        "tell-milliseconds",
        recording(times=[index * 20.0 for index in range(1101)]),
        "0 to 22000 s, but the rollout lasts 0 to 22 s (times must be in seconds)",
    ),
    tell_case("tell-past-the-end", recording(times=[index * 3 / 50 for index in range(1101)]), "the signals cover 0 to 66 s, but the rollout lasts 0 to 22 s"),
    tell_case("tell-short", recording(times=[index / 50 for index in range(200)]), "the signals cover 0 to 3.98 s"),
    tell_case("tell-late-start", recording(times=[5 + index / 50 for index in range(1101)]), "the signals cover 5 to 27 s"),
    tell_case("tell-one-sample", "t,x,y,z,force\n0,0.5,0,0.4,0\n", "1 sample; a recording needs at least 2"),
    tell_case("tell-coarse", recording(times=[float(index) for index in range(23)]), "one sample every 1 s, but the rollout is recorded at 50 samples/s"),
    tell_case("tell-uneven", recording(times=[index / 50 + (0.005 if index >= 500 else 0.0) for index in range(1101)]), "s.csv:502:"),
    tell_case("tell-backwards", recording(times=[index / 50 if index != 300 else 1.0 for index in range(1101)]), "s.csv:302: time must be strictly increasing"),
    tell_case("tell-crushing-force", recording(force=lambda i, t: 5e4 if i == 7 else 0.0), "s.csv:9: a force of 5e+04 N, above the 1000 N"),
    tell_case("tell-negative-force", recording(force=lambda i, t: -2e6), "a force of -2e+06 N"),
    tell_case("tell-nan", recording().replace("\n0.5,", "\nnan,", 1).replace("0.0,0.5,0.0", "0.0,nan,0.0", 1), "s.csv:2: column 'x' is nan"),
    tell_case("tell-inf", recording().replace("0.0,0.5,0.0", "0.0,inf,0.0", 1), "s.csv:2: column 'x' is inf"),
    tell_case("tell-no-x", "t,y,z\n0,0,0.4\n1,0,0.4\n", "missing column 'x'"),
    tell_case("tell-empty-file", "", "empty"),
    tell_case("tell-text-force", recording().replace(",0.0\n", ",heavy\n", 1), "s.csv:2: column 'force' has 'heavy', not a number"),
    tell_case("tell-duplicate-column", "t,x,y,z,x\n0,0.5,0,0.4,0.5\n", "duplicate column 'x'"),
    Case("ask-iterations-below-done", ["ask", "{case}/run", "-N", "2"], 5, "has 3 trials already; ask for at least 3", damage=lambda run: None),
    Case("ask-iterations-zero", ["ask", "{case}/run", "-N", "0"], 5, "--iterations 0: the run", damage=lambda run: None),
    Case("tell-empty-reason", ["tell", "{case}/run", "--failed", ""], 2, "--failed needs a reason", damage=ask_one_more),
    Case("tell-blank-reason", ["tell", "{case}/run", "--failed", "  "], 2, "--failed needs a reason", damage=ask_one_more),
    Case("tell-signals-and-failed", ["tell", "{case}/run", "{csv}", "--failed", "x"], 2, "(one of them)", damage=ask_one_more),
    Case("tell-no-arguments", ["tell"], 2, "Missing argument 'RUN_DIR'"),
    Case("tell-csv-missing", ["tell", "{case}/run", "{case}/nope.csv"], 4, "nope.csv", damage=ask_one_more),
    # --- object placements, executors, options -----------------------------------------------
    Case(
        "place-below-the-floor",
        ["optimize", str(ROOT / "configs" / "phi3.yaml"), "--place", "holder=0.6,0.2,-3", "--out", "{case}/out"],
        5,
        "--place: holder at z = -3 puts holder_left below the floor",
    ),
    Case(
        "task-place-below-the-floor",
        ["optimize", "{case}/t.yaml", "--out", "{case}/out"],
        5,
        "'place': holder at z = -1 puts holder_left below the floor",
        {
            "t.yaml": f"spec: {PHI1}\nbehaviour: {ROOT / 'configs' / 'behaviours' / 'pick_insert.yaml'}\nduration: 48\nplace: {{holder: [0.6, 0.2, -1]}}\nparameters: {{insert: {{durations: {{components: all}}}}}}\n"
        },
    ),
    Case(
        "task-place-yaw-degrees",
        ["optimize", "{case}/t.yaml", "--out", "{case}/out"],
        5,
        "'place.holder[3]': the yaw must be in radians, within two turns either way (got 90)",
        {
            "t.yaml": f"spec: {PHI1}\nbehaviour: {ROOT / 'configs' / 'behaviours' / 'pick_insert.yaml'}\nduration: 48\nplace: {{holder: [0.6, 0.2, 0.04, 90]}}\nparameters: {{insert: {{durations: {{components: all}}}}}}\n"
        },
    ),
    Case(
        "task-frame-unknown",
        ["optimize", "{case}/t.yaml", "--out", "{case}/out", "--quiet"],
        5,
        "t.yaml:4:48: 'parameters.insert.means.frame': the model has no frame nohere (its frames: base, shaft, holder)",
        {
            "t.yaml": f"spec: {ROOT / 'specs' / 'phi3_strict_objects.stl'}\nbehaviour: {ROOT / 'configs' / 'behaviours' / 'pick_insert.yaml'}\nduration: 48\nparameters: {{insert: {{means: {{components: [1], frame: nohere}}}}}}\n"
        },
    ),
    Case(
        "scene-rim-above-the-walls",
        ["rollout", "{model}", "--scene", "{case}/s.yaml"],
        5,
        "'frames.hole.rim' (5) puts the hole's rim at z = 5.04 m, outside the frame's objects (z 0.02 to 0.06 m)",
        {"s.yaml": HOLE_SCENE.format(rim=5.0)},
    ),
    Case(
        "scene-rim-below-the-walls",
        ["rollout", "{model}", "--scene", "{case}/s.yaml"],
        5,
        "'frames.hole.rim' (-0.5) puts the hole's rim at z = -0.46 m",
        {"s.yaml": HOLE_SCENE.format(rim=-0.5)},
    ),
    task_case(
        "task-command-placeholder",
        "the command has {signal}: did you mean {signals}?",
        backend="command",
        command="'run {reference} {signal}'",
    ),
    task_case(
        "task-command-shell-placeholder",
        "the command has {refrence}: did you mean {reference}?",
        backend="command",
        command="{run: 'exec {refrence}', shell: true}",
    ),
    task_case("task-scene-relative", "'scene' names ../scenes/s.yaml, which does not exist (paths are relative to the task file)", scene="../scenes/s.yaml"),
    Case("optimize-ray-nothing-there", ["optimize", "{task}", "--ray", "127.0.0.1:1", "--out", "{case}/out"], 5, "--ray 127.0.0.1:1: nothing answers there"),
    Case("optimize-ray-not-an-address", ["optimize", "{task}", "--ray", "not an address!", "--out", "{case}/out"], 5, "not a cluster address"),
    Case("optimize-ray-bad-port", ["optimize", "{task}", "--ray", "127.0.0.1:99999", "--out", "{case}/out"], 5, "not a cluster address"),
    task_case("optimize-workers-zero", "--workers 0 must be from 1 to 256", extra=["--workers", "0"]),
    task_case("optimize-iterations-zero", "--iterations 0 must be at least 1", extra=["-N", "0"]),
    Case(
        "scene-max-force",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'safety.max_force' must be positive",
        {"s.yaml": "description: x\nsafety: {workspace: {lower: [0, 0, 0], upper: [1, 1, 1]}, max_speed: 1, max_force: -5}\n"},
    ),
    Case(
        "scene-symmetry",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'frames.cup.symmetry' must be a whole number",
        {
            "s.yaml": "description: x\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02]}\nframes:\n  cup: {position: [0.5, 0, 0.02], objects: [a], symmetry: 2.5}\n"
        },
    ),
    Case(
        "learn-min-spread", ["learn", "{demos}", "-o", "{case}/m.npz", "--min-spread", "5mm,3deg"], 6, "--min-spread 5mm,3deg: give auto, none, or a position"
    ),
    Case("learn-min-spread-units", ["learn", "{demos}", "-o", "{case}/m.npz", "--min-spread", "5cm,3deg,10%"], 6, "such as 5mm,5deg,10%"),
    Case(
        "learn-not-a-csv",
        ["learn", "{case}/d.txt", "-o", "{case}/m.npz"],
        4,
        "no such folder of demonstrations (or demonstration CSV file)",
        {"d.txt": "t,x\n"},
    ),
    Case(
        "behaviour-learn-in",
        ["rollout", "{case}/b.yaml", "--backend", "kinematic"],
        5,
        "'steps[0].learn_in' must list the frames",
        {"b.yaml": f"scene: free_space\nsteps:\n  - {{skill: a, demos: {ROOT / 'demos' / 'three_regions'}, learn_in: base}}\n"},
    ),
    Case(
        "behaviour-min-spread",
        ["rollout", "{case}/b.yaml", "--backend", "kinematic"],
        5,
        "'steps[0].min_spread' 5mm: give auto, none, or a position",
        {"b.yaml": f"scene: free_space\nsteps:\n  - {{skill: a, demos: {ROOT / 'demos' / 'three_regions'}, min_spread: 5mm}}\n"},
    ),
    Case(
        "behaviour-scene-relative",
        ["rollout", "{case}/b.yaml", "--backend", "kinematic"],
        5,
        "'scene' names scenes/s.yaml, which does not exist (paths are relative to the behaviour file)",
        {"b.yaml": f"scene: scenes/s.yaml\nsteps:\n  - {{skill: a, demos: {ROOT / 'demos' / 'three_regions'}}}\n"},
    ),
    # Sweeps
    Case("sweep-missing", ["sweep", "{case}/nope.yaml", "--out", "{case}/out"], 5, "no such YAML file"),
    Case("sweep-unknown-key", ["sweep", "{case}/s.yaml", "--out", "{case}/out"], 5, "unknown key 'jobs'", {"s.yaml": "tasks: [t.yaml]\njobs: 2\n"}),
    Case(
        "sweep-task-missing",
        ["sweep", "{case}/s.yaml", "--out", "{case}/out"],
        5,
        "'tasks' names t.yaml, which does not exist",
        {"s.yaml": "tasks: [t.yaml]\n"},
    ),
    Case(
        "sweep-bad-task",
        ["sweep", "{case}/s.yaml", "--out", "{case}/out"],
        5,
        "'duration' must be positive",
        {"s.yaml": "tasks: [t.yaml]\n", "t.yaml": task_text(duration="0")},
    ),
    Case(
        "sweep-bad-seeds",
        ["sweep", "{case}/s.yaml", "--out", "{case}/out"],
        5,
        "'seeds' must be at least 0",
        {"s.yaml": "tasks: [t.yaml]\nseeds: [1, -2]\n", "t.yaml": task_text()},
    ),
    Case(
        "sweep-out-is-file",
        ["sweep", "{case}/s.yaml", "--out", "{case}/f.txt"],
        8,
        "is a file; the sweep folder must be a folder",
        {"s.yaml": "tasks: [t.yaml]\n", "t.yaml": task_text(), "f.txt": "x"},
    ),
    Case("report-sweep-options", ["report", "{case}", "--out", "{case}/r"], 5, "a sweep folder's report is its table and sweep.png", {"sweep.csv": "cell\n"}),
    # Sizes and bounds a user can type, checked before any work
    Case("learn-restarts-huge", ["learn", "{demos}", "--restarts", "99999999999999999999", "-o", "{case}/m.npz"], 2, "is not in the range 1<=x<=1000"),
    Case("learn-spread-huge", ["learn", "{demos}", "--min-spread", "1e9m,400deg,10000%", "-o", "{case}/m.npz"], 6, "at most 1m, 180deg and 1000%"),
    Case(
        "learn-sidecar-yaw-huge",
        ["learn", "{case}", "-o", "{case}/m.npz"],
        5,
        "'frames.shaft.yaw' must be in radians, within two turns either way (got 1e+308)",
        {
            "demo_01.csv": "t,x,y,z\n0,0.4,0,0.3\n0.1,0.41,0,0.3\n0.2,0.42,0,0.3\n",
            "demo_01.frames.yaml": "frames:\n  shaft: {position: [0.4, 0, 0.05], yaw: 1e308}\n",
        },
    ),
    Case(
        "scene-symmetry-huge",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'frames.cup.symmetry' must be a whole number of yaws that give the same objects, 1 to 360",
        {
            "s.yaml": "description: d\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02]}\n"
            "frames:\n  cup: {position: [0.5, 0, 0.02], objects: [a], symmetry: 1000000000}\n"
        },
    ),
    Case(
        "scene-into-no-hole",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'frames.peg.into' must name another frame with a 'rim'",
        {
            "s.yaml": "description: d\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02], mass: 0.1}\n"
            "frames:\n  peg: {position: [0.5, 0, 0.02], objects: [a], into: cup}\n"
        },
    ),
    Case(
        "place-above-workspace",
        ["rollout", str(ROOT / "configs" / "behaviours" / "pick_insert.yaml"), "--backend", "kinematic", "--place", "holder=0.6,0.2,5"],
        5,
        "holder at z = 5 is above the scene's workspace (its top at z = 0.6); heights are in metres",
    ),
    Case(
        "place-yaw-in-degrees",
        ["rollout", "{model}", "--scene", "pick_insert", "--backend", "kinematic", "--place", "holder=0.6,0.2,0.04,90"],
        5,
        "the yaw must be in radians",
    ),
    task_case("task-scene-folder", "t.yaml:8:1: 'scene' names ./, which is a folder", scene="./"),
    Case("task-yaml-too-deep", ["optimize", "{case}/t.yaml"], 5, "the YAML nests too deeply to read", {"t.yaml": "x: " + "[" * 20000 + "]" * 20000 + "\n"}),
    Case("optimize-nothing-given", ["optimize"], 5, "give a task file (e.g. configs/phi1.yaml), or --spec SPEC"),
    Case(
        "optimize-spec-without-task",
        ["optimize", "--spec", "{case}/s.stl"],
        5,
        "no task file in configs/ names this spec; give a task file, or --demos DIR",
        {"s.stl": "phi := F x > 0\n"},
    ),
    Case(
        "optimize-task-and-demos",
        ["optimize", "{case}/t.yaml", "--demos", "{demos}"],
        5,
        "--demos and --model build a task without a task file",
        {"t.yaml": task_text()},
    ),
    Case(
        "optimize-default-task-object-skill",
        ["optimize", "--spec", "{case}/s.stl", "--demos", str(ROOT / "demos" / "insert")],
        5,
        "the demonstrations have frame sidecars; a skill that follows objects needs a task file",
        {"s.stl": "phi := F x > 0\n"},
    ),
    Case(
        "rollout-command-fails-names-no-deleted-file",
        ["rollout", "{model}", "--backend", "command", "--command", "sh -c 'echo motor fault >&2; exit 3'"],
        7,
        "the command exited with status 3: motor fault",
    ),
    Case(
        "optimize-placements-on-command-backend",
        ["optimize", "{case}/t.yaml", "--backend", "command", "--command", "true"],
        5,
        "several placements need a simulated backend (the command backend executes one reference per trial)",
        {
            "t.yaml": f"spec: {ROOT / 'specs' / 'phi3_strict_objects.stl'}\nbehaviour: {ROOT / 'configs' / 'behaviours' / 'pick_insert.yaml'}\nduration: 48\n"
            "placements:\n  - {holder: {position: [0.6, 0.2, 0.04]}}\n  - {holder: {position: [0.5, 0.2, 0.04]}}\n"
            "parameters:\n  pick: {durations: {components: all}}\n"
        },
    ),
    Case("learn-sets-output-is-a-model-file", ["learn", str(ROOT / "demos"), "-o", "{case}/m.npz"], 5, "holds one folder per skill (insert, pick"),
    Case("learn-sets-output-is-a-file", ["learn", str(ROOT / "demos"), "-o", "{case}/f"], 8, "is a file; the models folder must be a folder", {"f": "x"}),
    Case("optimize-spec-missing", ["optimize", "--spec", "{case}/nope.stl"], 5, "no such spec file"),
    Case(
        "optimize-default-task-demos-missing",
        ["optimize", "--spec", "{case}/s.stl", "--demos", "{case}/nope"],
        4,
        "no such folder of demonstrations",
        {"s.stl": "phi := F x > 0\n"},
    ),
    Case(
        "optimize-default-task-model-missing",
        ["optimize", "--spec", "{case}/s.stl", "--model", "{case}/nope.npz"],
        6,
        "nope.npz",
        {"s.stl": "phi := F x > 0\n"},
    ),
    Case(
        "scene-rim-not-a-number",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'frames.cup.rim' must be a number",
        {
            "s.yaml": "description: d\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02]}\n"
            "frames:\n  cup: {position: [0.5, 0, 0.02], objects: [a], rim: high}\n"
        },
    ),
    Case(
        "scene-into-a-fixed-object",
        ["rollout", "{model}", "--scene", "{case}/s.yaml", "--backend", "kinematic"],
        5,
        "'frames.peg.into': the frame's first object, a, must be movable",
        {
            "s.yaml": "description: d\nobjects:\n  - {name: a, shape: box, size: [0.01, 0.01, 0.01], position: [0.5, 0, 0.02]}\n"
            "  - {name: b, shape: box, size: [0.02, 0.02, 0.02], position: [0.6, 0, 0.02]}\n"
            "frames:\n  peg: {position: [0.5, 0, 0.02], objects: [a], into: cup}\n  cup: {position: [0.6, 0, 0.02], objects: [b], rim: 0.02}\n"
        },
    ),
    Case(
        "learn-sets-one-bad-writes-nothing",
        ["learn", "{case}/d", "-o", "{case}/models", "-K", "2"],
        4,
        "b/demo_01.csv",
        {
            "d/a/demo_01.csv": "t,x,y,z\n" + "".join(f"{0.1 * i:.1f},{0.4 + 0.01 * i},0,0.3\n" for i in range(8)),
            "d/b/demo_01.csv": "t,x,y,z\n0,0.4,0,0.3\n0.1,nan,0,0.3\n",
        },
    ),
    Case(
        "optimize-default-task-demos-and-model",
        ["optimize", "--spec", "{case}/s.stl", "--demos", "{demos}", "--model", "{model}"],
        5,
        "give --demos DIR or --model FILE for the default task, not both",
        {"s.stl": "phi := F x > 0\n"},
    ),
    Case(
        "optimize-place-yaw-huge",
        ["optimize", "{case}/t.yaml", "--place", "holder=0.6,0.2,0.04,1e308"],
        5,
        "the yaw must be in radians, within two turns either way (got 1e+308)",
        {
            "t.yaml": f"spec: {ROOT / 'specs' / 'phi3_strict_objects.stl'}\nbehaviour: {ROOT / 'configs' / 'behaviours' / 'pick_insert.yaml'}\nduration: 48\nparameters:\n  pick: {{durations: {{components: all}}}}\n"
        },
    ),
    tell_case("tell-tilt-in-degrees", recording(tilt=lambda i, t: 90.0), "tilt = 90, but the hand's tilt (rad) lies in [0, 3.14159]"),
    tell_case("tell-tilt-huge", recording(tilt=lambda i, t: 1e9), "tilt = 1e+09, but the hand's tilt (rad) lies in [0, 3.14159]"),
    tell_case("tell-tilt-negative", recording(tilt=lambda i, t: -3), "tilt = -3, but the hand's tilt"),
    tell_case("tell-force-negative", recording(force=lambda i, t: -50), "a force of -50 N; `force` is the norm of the contact force, never negative"),
    tell_case(
        "tell-quaternion-norm-10",
        recording(qx=lambda i, t: 0, qy=lambda i, t: 0, qz=lambda i, t: 0, qw=lambda i, t: 10),
        "the orientation qx, qy, qz, qw has norm 10",
    ),
]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory, learned_model_file) -> dict[str, Path]:
    """The shared inputs: a model, a valid task and a finished 3-trial run."""
    from stl_lfd.optim import finish_run, load_task, start_run

    folder = tmp_path_factory.mktemp("workspace")
    task = folder / "task.yaml"
    task.write_text(TASK.replace("@spec@", PHI1).replace("@model@", str(learned_model_file)))
    with start_run(load_task(task), folder / "run") as prepared:
        finish_run(prepared)
    from stl_lfd.hsmm import load_model, save_model

    slow_skill = load_model(learned_model_file)
    slow_skill.duration_means_[:] = 1e9  # states that last 30 years: retrieval would need terabytes
    save_model(slow_skill, folder / "slow.npz")
    from stl_lfd.optim.runs.asktell import ask

    shutil.copytree(folder / "run", folder / "asked")
    ask(folder / "asked", trials=4)
    ASKED_RUN[:] = [folder / "asked"]
    return {"model": learned_model_file, "task": task, "run": folder / "run", "slow_model": folder / "slow.npz"}


def snapshot(*folders: Path) -> dict[str, str]:
    """Every file under `folders` (but the run lock, whose PID changes) -> digest of its bytes."""
    files = {}
    for folder in folders:
        for path in sorted(Path(folder).rglob("*")):
            if path.is_file() and path.name != ".lock":
                files[str(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
    return files


def test_the_corpus_is_large_and_its_names_unique():
    assert len(CASES) >= 100
    assert len({case.id for case in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[case.id for case in CASES])
def test_bad_input(case: Case, workspace, tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    folder = tmp_path / "case"
    folder.mkdir()
    for name, content in case.files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(
            content.replace("@spec@", PHI1).replace("@model@", str(workspace["model"]))
        )
    if case.damage is not None:
        shutil.copytree(workspace["run"], folder / "run")
        case.damage(folder / "run")
    places = {"case": folder, "csv": ROOT / "examples" / "three_regions.csv", "demos": ROOT / "demos" / "three_regions", "spec": PHI1, **workspace}
    arguments = [argument.format(**{key: str(value) for key, value in places.items()}) for argument in case.arguments]
    before = snapshot(folder, workspace["run"], workspace["model"].parent, ROOT / "specs", ROOT / "configs")
    result = runner.invoke(app, arguments)
    assert result.exit_code == case.code, result.stderr + result.stdout
    assert "Traceback" not in result.stderr and result.stdout == ""
    lines = result.stderr.splitlines()
    assert lines and lines[0].startswith("error: ") or case.code == 2, result.stderr
    if case.code != 2:
        extra = lines[1:]
        assert not extra or (len(extra) == 2 and extra[1].strip() == "^"), result.stderr  # a spec error's line and caret
    assert case.message in result.stderr, result.stderr
    after = snapshot(folder, workspace["run"], workspace["model"].parent, ROOT / "specs", ROOT / "configs")
    assert after == before, "the command changed its inputs or an existing run"


@pytest.mark.slow
def test_a_run_without_trials_yet_still_reports(workspace, tmp_path):
    shutil.copytree(workspace["run"], tmp_path / "run")
    (tmp_path / "run" / "trials.jsonl").write_text("")
    result = runner.invoke(app, ["report", str(tmp_path / "run"), "--out", str(tmp_path / "report")])
    assert result.exit_code == 0, result.stderr
    assert (tmp_path / "report" / "index.html").exists()
