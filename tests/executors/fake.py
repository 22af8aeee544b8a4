"""A test executor: executes like the kinematic backend, or misbehaves as EXECUTOR_MODE says.

    fake.py REFERENCE SIGNALS

EXECUTOR_MODE: ok (default), exit1, hang, garbage, noforce, nothing, delete, env.
EXECUTOR_BAD_TRIAL: the trial to misbehave on (default: every trial but 0, the unoptimised skill).
EXECUTOR_MARKER: a file to which each run appends its trial number.
"""

import os
import subprocess
import sys
import time

from stl_lfd.signals import write_signal_csv
from stl_lfd.sim import execute, load_scene, read_reference_csv

reference_path, signals_path = sys.argv[1:3]
mode = os.environ.get("EXECUTOR_MODE", "ok")
trial = int(os.environ["STLOPT_TRIAL"])
bad_trial = int(os.environ.get("EXECUTOR_BAD_TRIAL", "-1"))
if os.environ.get("EXECUTOR_MARKER"):
    with open(os.environ["EXECUTOR_MARKER"], "a") as marker:
        marker.write(f"{trial}\n")
misbehave = trial == bad_trial if bad_trial >= 0 else trial > 0


def record(drop=()):
    reference = read_reference_csv(reference_path)
    signals = execute(reference, load_scene(os.environ.get("STLOPT_SCENE", "free_space")), "kinematic", float(os.environ.get("STLOPT_RATE", "100"))).signals
    for name in drop:
        del signals.columns[name]
    write_signal_csv(signals, signals_path, digits=17)


if misbehave and mode == "exit1":
    print("starting", file=sys.stderr)
    print("motor fault on joint 4", file=sys.stderr)
    sys.exit(1)
if misbehave and mode == "hang":
    child = subprocess.Popen(["sleep", "600"])
    with open(os.environ["EXECUTOR_CHILD_PID"], "w") as stream:
        stream.write(f"{child.pid}\n")
    time.sleep(600)
if misbehave and mode == "garbage":
    with open(signals_path, "w") as stream:
        stream.write("this is not,a signal file\nat,all\n")
    sys.exit(0)
if misbehave and mode == "nothing":
    sys.exit(0)
if misbehave and mode == "delete":
    record()
    os.remove(reference_path)
    sys.exit(0)
if mode == "env":
    for name in ("STLOPT_TRIAL", "STLOPT_RUN_DIR", "STLOPT_SCENE", "STLOPT_RATE", "STLOPT_REFERENCE", "STLOPT_SIGNALS"):
        print(f"{name}={os.environ[name]}")
    print(f"argv={sys.argv[1:]}")
record(drop=("force",) if misbehave and mode == "noforce" else ())
