"""An executor for `backend: command` and `stlopt ask`: plays a reference CSV on the simulated
Panda, in its own process, and writes the signals it recorded.

    python examples/pybullet_executor.py REFERENCE_CSV SIGNALS_CSV [--scene NAME_OR_FILE] [--rate HZ]

Run by stlopt (task file `command: python pybullet_executor.py {reference} {signals}`), it takes
the scene and the recording rate from STLOPT_SCENE and STLOPT_RATE; by hand, from --scene and
--rate (default: free_space, 100 samples/s). A real robot's executor does the same with its own
controller: read the reference (positions and the hand's orientation), move through it, record
t, x, y, z (and force, gripper, qx, qy, qz, qw, tilt), write the CSV, exit 0; see the
documentation's page on execution and real robots.

It uses the same PyBullet backend as `stlopt optimize --backend pybullet` and writes numbers
that read back exactly, so a run through this executor gives the same trials and robustness.
"""

from __future__ import annotations

import argparse
import os
import sys

from stl_lfd.errors import StlLfdError
from stl_lfd.signals import write_signal_csv
from stl_lfd.sim import execute, load_scene, new_backend, read_reference_csv


def main() -> int:
    parser = argparse.ArgumentParser(description="Play a reference CSV on the simulated Panda and write the recorded signals.")
    parser.add_argument("reference", help="reference CSV (t,x,y,z,gripper,skill,state,event,qx,qy,qz,qw)")
    parser.add_argument("signals", help="signal CSV to write")
    parser.add_argument("--scene", default=os.environ.get("STLOPT_SCENE", "free_space"), help="built-in scene name or scene file")
    parser.add_argument("--rate", type=float, default=float(os.environ.get("STLOPT_RATE", "100")), help="recording rate (samples/s)")
    arguments = parser.parse_args()
    try:
        reference = read_reference_csv(arguments.reference)
        with new_backend("pybullet") as backend:
            rollout = execute(reference, load_scene(arguments.scene), backend, arguments.rate)
        write_signal_csv(rollout.signals, arguments.signals, digits=17)
    except StlLfdError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
