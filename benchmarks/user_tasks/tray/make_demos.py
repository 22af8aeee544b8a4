"""Demonstrations of the tray task, as recorded by kinesthetic teaching: a person guides the
Panda's hand to pick the can from the table (skill `pick`) and then to put it into the tray
(skill `place`). The fingers are closed and opened by the behaviour's grasp and release actions,
so the files hold the hand's path only (t, x, y, z at 30 Hz, metres, robot base frame).

THE FLAW: the demonstrator lowers the can 1.6 cm off the tray's centre, towards its +x wall. The
can has 1.4 cm of room to each wall, so the learned skill sets it down on the wall's top edge:
the hand presses the can onto the wall and the can ends up leaning on it, not standing inside.

Each demonstration has the can and the tray at other places on the table (within +-4 cm of the
scene's poses), given in a frame sidecar beside it (demo_NN.frames.yaml). The hand path goes
through waypoints with minimum-jerk segments, timing that varies from one demonstration to the
next, a slow sway of the hand and 0.3 mm of sensor noise.

Run from this folder: python make_demos.py   (fixed seed: the same files every time)
"""

from pathlib import Path

import numpy as np

SEED = 8
COUNT = 5
RATE_HZ = 30
HERE = Path(__file__).resolve().parent
HOME = np.array([0.42, 0.0, 0.40])
CAN = np.array([0.45, -0.22, 0.055])  # the can's centre, as in scene.yaml
TRAY = np.array([0.55, 0.18, 0.026])  # the centre of the tray's floor
CAN_HALF_HEIGHT = 0.035
GRASP_IN_CAN = np.array([0.0, 0.0, 0.015])  # the hand closes 1.5 cm above the can's centre
FLAW = np.array([0.016, 0.0, 0.0])  # where the demonstrator sets the can down, from the centre
SPREAD = 0.04


def stratified(rng, count, spread):
    return rng.permutation((np.arange(count) + rng.uniform(size=count)) / count * 2 * spread - spread)


def path_through(rng, waypoints):
    """waypoints: (position, seconds to get there). Minimum-jerk segments, human timing."""
    knots, points = [0.0], [waypoints[0][0]]
    for position, seconds in waypoints[1:]:
        knots.append(knots[-1] + seconds * rng.lognormal(0.0, 0.12))
        points.append(position)
    times = np.arange(int(knots[-1] * RATE_HZ) + 1) / RATE_HZ
    path = np.empty((times.size, 3))
    for i, t in enumerate(times):
        k = min(np.searchsorted(knots, t, side="right") - 1, len(knots) - 2)
        s = np.clip((t - knots[k]) / (knots[k + 1] - knots[k]), 0.0, 1.0)
        path[i] = points[k] + (points[k + 1] - points[k]) * (10 * s**3 - 15 * s**4 + 6 * s**5)
    window = np.hanning(31) / np.hanning(31).sum()
    sway = (
        np.stack([np.convolve(rng.normal(0, 1, times.size), window, mode="same") for _ in range(3)], axis=1) * 0.004
    )  # a slow sway of the guiding hand, under a millimetre
    return times, path + sway + rng.normal(0, 0.0003, path.shape)


def pick(rng, can):
    grasp = can + GRASP_IN_CAN + rng.normal(0, 0.001, 3)
    above = grasp + [0, 0, 0.12] + rng.normal(0, 0.005, 3)
    return path_through(rng, [(HOME, 0), (HOME, 1.5), (above, 4.5), (grasp, 3.0), (grasp, 1.5)])


def place(rng, can, tray):
    grasp = can + GRASP_IN_CAN
    stop = tray + FLAW + [0, 0, CAN_HALF_HEIGHT] + GRASP_IN_CAN
    stop = stop + np.append(rng.normal(0, 0.004, 2), rng.uniform(0.0, 0.002))  # lowered until it touches
    lifted = grasp + [0, 0, 0.18] + rng.normal(0, 0.005, 3)
    hover = stop + [0, 0, 0.10] + np.append(rng.normal(0, 0.003, 2), 0.0)
    return path_through(rng, [(grasp, 0), (grasp, 1.0), (lifted, 2.5), (hover, 3.0), (hover, 1.2), (stop, 2.5), (stop, 1.5)])


def write(path, times, positions):
    with open(path, "w") as out:
        out.write("t,x,y,z\n")
        for t, (x, y, z) in zip(times, positions):
            out.write(f"{t:.4f},{x:.5f},{y:.5f},{z:.5f}\n")


def sidecar(path, frames):
    lines = ["frames:"] + [f"  {name}: {{position: [{p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}], yaw: 0.0}}" for name, p in frames.items()]
    path.write_text("\n".join(lines) + "\n")


def main():
    rng = np.random.default_rng(SEED)
    offsets = [stratified(rng, COUNT, SPREAD) for _ in range(4)]
    for skill in ("pick", "place"):
        (HERE / "demos" / skill).mkdir(parents=True, exist_ok=True)
        for old in (HERE / "demos" / skill).glob("demo_*"):
            old.unlink()
    for i in range(COUNT):
        can = CAN + [offsets[0][i], offsets[1][i], 0.0]
        tray = TRAY + [offsets[2][i], offsets[3][i], 0.0]
        stem = f"demo_{i + 1:02d}"
        write(HERE / "demos" / "pick" / f"{stem}.csv", *pick(rng, can))
        sidecar(HERE / "demos" / "pick" / f"{stem}.frames.yaml", {"can": can})
        write(HERE / "demos" / "place" / f"{stem}.csv", *place(rng, can, tray))
        sidecar(HERE / "demos" / "place" / f"{stem}.frames.yaml", {"can": can, "tray": tray})


if __name__ == "__main__":
    main()
