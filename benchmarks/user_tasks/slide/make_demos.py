"""Write demos/ for the slide task: five demonstrations of pushing the box along the table
(towards +y) with the closed hand until it rests on the mark, each with the box and the mark at
other places (frame sidecars beside each CSV).

FLAW: the demonstrator stopped pushing too early: the box ends 0.5 to 3.5 cm (2 cm on
average) short of the mark, whose tolerance is 1 cm.

Each demonstration: from the home pose to above a point behind the box, down to the box's
mid-height, push it along y, stop, lift and go back up. Minimum-jerk segments between
waypoints, human timing variation, 0.5 mm sensor noise, 50 Hz.

Run from this folder or anywhere: python make_demos.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "demos"
SEED = 5
COUNT = 5
RATE_HZ = 50
NOISE_M = 0.0005
HOME = np.array([0.42, 0.0, 0.40])
BOX = np.array([0.50, -0.10, 0.045])  # the scene's box frame (its centre)
MARK = np.array([0.50, 0.06, 0.02])  # the scene's mark frame (on the table's top)
HALF_BOX = 0.025
FINGER = 0.025  # from the grasp point to the face of the closed fingers that touches the box
HAND_Z = 0.035  # the grasp point low on the box: fingertips 7 mm over the table
SHORT_M = (0.005, 0.035)  # how far short of the mark the box was left (the flaw)


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


def demonstration(rng, box, mark, short):
    def near(point, spread):
        return np.asarray(point) + rng.normal(0, spread, 3) * np.array([1, 1, 0.5])

    behind = np.array([box[0], box[1] - HALF_BOX - FINGER - 0.04, HAND_Z])
    touch = np.array([box[0], box[1] - HALF_BOX - FINGER, HAND_Z])
    end = np.array([mark[0], mark[1] - short - HALF_BOX - FINGER, HAND_Z]) + rng.normal(0, 0.001, 3) * np.array([1, 0, 0.5])
    phases = [  # (target, mean seconds to reach it, spread)
        (HOME, 0.0, 0.0),
        (HOME, 1.5, 0.3),
        (near(behind + np.array([0, 0, 0.10]), 0.004), 3.0, 0.4),
        (near(behind, 0.001), 1.5, 0.2),
        (touch, 1.2, 0.2),
        (end, 4.0, 0.5),  # the push
        (end, 1.5, 0.3),  # stop and make sure the box has stopped
        (near(end + np.array([0, -0.03, 0.12]), 0.004), 1.5, 0.2),
        (near(HOME + np.array([0, 0, -0.05]), 0.01), 2.5, 0.3),
    ]
    waypoints, clock = [(0.0, phases[0][0])], 0.0
    for target, seconds, spread in phases[1:]:
        clock += max(0.5, seconds + rng.normal(0, spread))
        waypoints.append((clock, target))
    times = np.arange(int(round((clock + 1.0) * RATE_HZ)) + 1) / RATE_HZ
    path = minimum_jerk(times, waypoints) + rng.normal(0, NOISE_M, (times.size, 3))
    return times, path


def main():
    rng = np.random.default_rng(SEED)
    OUT.mkdir(exist_ok=True)
    for old in [*OUT.glob("demo_*.csv"), *OUT.glob("demo_*.frames.yaml")]:
        old.unlink()
    dx, dy = stratified(rng, COUNT, -0.04, 0.04), stratified(rng, COUNT, -0.03, 0.03)
    distance = stratified(rng, COUNT, 0.14, 0.18)  # where the mark was taped, ahead of the box
    shorts = stratified(rng, COUNT, *SHORT_M)
    for i in range(COUNT):
        box = BOX + np.array([dx[i], dy[i], 0.0])
        mark = np.array([box[0] + rng.normal(0, 0.002), box[1] + distance[i], MARK[2]])
        times, path = demonstration(rng, box, mark, shorts[i])
        stem = OUT / f"demo_{i + 1:02d}"
        with open(f"{stem}.csv", "w") as f:
            f.write("t,x,y,z\n")
            for t, (x, y, z) in zip(times, path):
                f.write(f"{t:.2f},{x:.5f},{y:.5f},{z:.5f}\n")
        sidecar = "frames:\n"
        for name, pose in (("box", box), ("mark", mark)):
            sidecar += f"  {name}: {{position: [{', '.join(f'{v:.4f}' for v in pose)}], yaw: 0.0}}\n"
        Path(f"{stem}.frames.yaml").write_text(sidecar)


if __name__ == "__main__":
    main()
