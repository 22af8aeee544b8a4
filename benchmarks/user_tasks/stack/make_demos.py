"""Demonstrations of the stack task, as recorded by kinesthetic teaching: a person guides the
Panda's hand to pick the cube from the table (skill `pick`) and to set it on the lower block
(skill `place`). The fingers are closed and opened by the behaviour's grasp and release
actions, so the files hold the hand's path only (t, x, y, z at 30 Hz, metres, robot base frame).

THE FLAW: the demonstrator is slow and careful: pick and place take about 33 s of hand motion, with long
pauses and a slow descent; the cell needs the cube stacked and let go within 30 s.

Each demonstration has the cube and the lower block at other places on the table (within +-4 cm
of the scene's poses), given in a frame sidecar beside it (demo_NN.frames.yaml). The hand path
goes through waypoints with minimum-jerk segments, timing that varies from one demonstration to
the next, a slow sway of the hand and 0.3 mm of sensor noise.

Run from this folder: python make_demos.py   (fixed seed: the same files every time)
"""

from pathlib import Path

import numpy as np

SEED = 5
COUNT = 5
RATE_HZ = 30
HERE = Path(__file__).resolve().parent
HOME = np.array([0.42, 0.0, 0.40])
BLOCK = np.array([0.45, -0.22, 0.04])  # the cube's centre, as in scene.yaml
LOWER = np.array([0.55, 0.18, 0.04])  # the lower block's centre
STACKED_IN_LOWER = np.array([0.0, 0.0, 0.04])  # the cube's centre when it sits on the lower block
GRASP_IN_BLOCK = np.array([0.0, 0.0, 0.005])
SPREAD = 0.04
TIMING_SPREAD = 0.18  # people take more or less time for each move


def stratified(rng, count, spread):
    return rng.permutation((np.arange(count) + rng.uniform(size=count)) / count * 2 * spread - spread)


def path_through(rng, waypoints):
    """waypoints: (position, seconds to get there). Minimum-jerk segments, human timing."""
    knots, points = [0.0], [waypoints[0][0]]
    for position, seconds in waypoints[1:]:
        knots.append(knots[-1] + seconds * rng.lognormal(0.0, TIMING_SPREAD))
        points.append(position)
    times = np.arange(int(knots[-1] * RATE_HZ) + 1) / RATE_HZ
    path = np.empty((times.size, 3))
    for i, t in enumerate(times):
        k = min(np.searchsorted(knots, t, side="right") - 1, len(knots) - 2)
        s = np.clip((t - knots[k]) / (knots[k + 1] - knots[k]), 0.0, 1.0)
        path[i] = points[k] + (points[k + 1] - points[k]) * (10 * s**3 - 15 * s**4 + 6 * s**5)
    window = np.hanning(31) / np.hanning(31).sum()
    sway = np.stack([np.convolve(rng.normal(0, 1, times.size), window, mode="same") for _ in range(3)], axis=1) * 0.004
    return times, path + sway + rng.normal(0, 0.0003, path.shape)


def pick(rng, block):
    grasp = block + GRASP_IN_BLOCK + rng.normal(0, 0.001, 3)
    above = grasp + [0, 0, 0.12] + rng.normal(0, 0.005, 3)
    return path_through(rng, [(HOME, 0), (HOME, 2.0), (above, 5.5), (grasp, 4.0), (grasp, 2.0)])


def place(rng, block, lower):
    grasp = block + GRASP_IN_BLOCK
    stop = lower + STACKED_IN_LOWER + GRASP_IN_BLOCK
    stop = stop + np.append(rng.normal(0, 0.003, 2), rng.uniform(0.0, 0.002))  # lowered until it touches
    lifted = grasp + [0, 0, 0.15] + rng.normal(0, 0.005, 3)
    hover = stop + [0, 0, 0.08] + np.append(rng.normal(0, 0.003, 2), 0.0)
    return path_through(rng, [(grasp, 0), (grasp, 1.5), (lifted, 3.5), (hover, 5.0), (hover, 2.5), (stop, 4.5), (stop, 2.0)])


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
        block = BLOCK + [offsets[0][i], offsets[1][i], 0.0]
        lower = LOWER + [offsets[2][i], offsets[3][i], 0.0]
        stem = f"demo_{i + 1:02d}"
        write(HERE / "demos" / "pick" / f"{stem}.csv", *pick(rng, block))
        sidecar(HERE / "demos" / "pick" / f"{stem}.frames.yaml", {"block": block})
        write(HERE / "demos" / "place" / f"{stem}.csv", *place(rng, block, lower))
        sidecar(HERE / "demos" / "place" / f"{stem}.frames.yaml", {"block": block, "lower": lower})


if __name__ == "__main__":
    main()
