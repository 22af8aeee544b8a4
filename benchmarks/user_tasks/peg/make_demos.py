"""Write demos/pick/ and demos/insert/ for the peg task: five demonstrations each of picking the
round peg and inserting it into the round hole, with the peg and the holder at other places
each time (frame sidecars beside each CSV).

FLAW: the demonstrator lowered the peg 5 mm off the hole's axis (along the holder's x), more
than the 3.5 mm of clearance, so the learned insertion puts the peg onto the hole's rim.

pick: from the home pose to above the peg, down around it and stop. insert: from the grasp
pose, lift, carry over the holder, hover, lower straight down and stop with the peg's bottom
5 mm above the table. Minimum-jerk segments between waypoints, human timing variation,
0.5 mm sensor noise, 50 Hz.

Run from this folder or anywhere: python make_demos.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "demos"
SEED = 3
COUNT = 5
RATE_HZ = 50
NOISE_M = 0.0005
HOME = np.array([0.42, 0.0, 0.40])
PEG = np.array([0.45, -0.25, 0.07])  # the scene's peg frame (its centre)
HOLDER = np.array([0.55, 0.20, 0.04])  # the scene's holder frame (the hole's axis, mid-height)
GRASP_IN_PEG = np.array([0.0, 0.0, 0.025])  # the grasp point 2.5 cm below the peg's top
STOP_IN_HOLDER = np.array([0.0, 0.0, 0.06])  # the peg's bottom 5 mm above the table
SHIFT = np.array([0.005, 0.0, 0.0])  # the flaw: 5 mm off the hole's axis
# where each demonstration stops around the shifted point (mm): people never stop twice alike
STOP_SPREAD_MM = [(-5, 4, 3), (4, -5, -2), (0, 1, 4), (-3, -5, 0), (5, 5, 6)]


def stratified(rng, count, low, high):
    """`count` values over [low, high], one in each of `count` equal slices, shuffled."""
    return rng.permutation(low + (np.arange(count) + rng.uniform(size=count)) / count * (high - low))


def minimum_jerk(times, waypoints):
    positions = np.repeat(waypoints[0][1][None], times.size, axis=0)
    for (t0, p0), (t1, p1) in zip(waypoints[:-1], waypoints[1:]):
        inside = (times >= t0) & (times <= t1)
        phase = (times[inside] - t0) / (t1 - t0)
        blend = 10 * phase**3 - 15 * phase**4 + 6 * phase**5
        positions[inside] = p0 + (p1 - p0) * blend[:, None]
    positions[times > waypoints[-1][0]] = waypoints[-1][1]
    return positions


def demonstration(rng, phases, hold_end):
    waypoints, clock = [(0.0, phases[0][0])], 0.0
    for target, seconds, spread in phases[1:]:
        clock += max(0.4, seconds + rng.normal(0, spread))
        waypoints.append((clock, target))
    times = np.arange(int(round((clock + hold_end) * RATE_HZ)) + 1) / RATE_HZ
    return times, minimum_jerk(times, waypoints) + rng.normal(0, NOISE_M, (times.size, 3))


def near(rng, point, spread):
    return np.asarray(point) + rng.normal(0, spread, 3) * np.array([1, 1, 0.4])


def pick(rng, peg):
    grasp = peg + GRASP_IN_PEG
    above = grasp + np.array([0, 0, 0.12])
    phases = [
        (HOME, 0.0, 0.0),
        (HOME, 1.5, 0.3),
        (near(rng, above, 0.004), 4.0, 0.5),
        (above + rng.normal(0, 0.001, 3), 1.5, 0.3),
        (grasp + rng.normal(0, 0.0008, 3), 2.5, 0.3),
    ]
    return demonstration(rng, phases, hold_end=1.5)


def insert(rng, peg, holder, index):
    grasp = peg + GRASP_IN_PEG
    stop = holder + STOP_IN_HOLDER + SHIFT + np.array(STOP_SPREAD_MM[index]) / 1000
    hover = near(rng, stop + np.array([0, 0, 0.12]), 0.002)
    phases = [
        (grasp, 0.0, 0.0),
        (grasp, 1.0, 0.2),
        (near(rng, grasp + np.array([0, 0, 0.14]), 0.003), 2.0, 0.3),
        (near(rng, [0.52, -0.02, 0.25], 0.01), 3.0, 0.4),
        (hover, 3.0, 0.4),
        (hover, 2.0, 0.3),  # steady above the hole, then straight down
        (stop, 1.5, 0.2),
    ]
    return demonstration(rng, phases, hold_end=1.5)


def write(folder, stem, times, path, frames):
    with open(folder / f"{stem}.csv", "w") as f:
        f.write("t,x,y,z\n")
        for t, (x, y, z) in zip(times, path):
            f.write(f"{t:.2f},{x:.5f},{y:.5f},{z:.5f}\n")
    text = "frames:\n" + "".join(f"  {name}: {{position: [{', '.join(f'{v:.4f}' for v in pose)}], yaw: 0.0}}\n" for name, pose in frames.items())
    (folder / f"{stem}.frames.yaml").write_text(text)


def main():
    rng = np.random.default_rng(SEED)
    offsets = [stratified(rng, COUNT, -0.06, 0.06) for _ in range(4)]
    for name in ("pick", "insert"):
        (OUT / name).mkdir(parents=True, exist_ok=True)
        for old in [*(OUT / name).glob("demo_*.csv"), *(OUT / name).glob("demo_*.frames.yaml")]:
            old.unlink()
    for i in range(COUNT):
        peg = PEG + np.array([offsets[0][i], offsets[1][i], 0.0])
        holder = HOLDER + np.array([offsets[2][i], offsets[3][i], 0.0])
        stem = f"demo_{i + 1:02d}"
        write(OUT / "pick", stem, *pick(rng, peg), {"peg": peg})
        write(OUT / "insert", stem, *insert(rng, peg, holder, i), {"peg": peg, "holder": holder})


if __name__ == "__main__":
    main()
