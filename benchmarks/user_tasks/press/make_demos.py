"""Write demos/ for the press task: five demonstrations of pressing the button with the closed
hand, each with the button at another place on the table (frame sidecar beside each CSV).

FLAW: the demonstrator pressed too hard. Each press pushes the hand 18 to 28 mm below the
point where the fingertips meet the button's top (about 7 to 11 N with the arm's 400 N/m),
9 N on average, so the learned skill presses above the 8 N the task allows.

The recorded z during the press is the hand's commanded (equilibrium) pose, below the button's
top: with the compliant arm, the force is the stiffness times how far the command goes below
the surface, and that is the only way a position demonstration can carry a force.

Each demonstration: from the home pose over to 10 cm above the button, down onto it, press
and hold for 2.5 to 3.5 s, lift, and back towards home. Minimum-jerk segments between
waypoints, human timing variation, 0.5 mm sensor noise, 50 Hz.

Run from this folder or anywhere: python make_demos.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "demos"
SEED = 7
COUNT = 5
RATE_HZ = 50
NOISE_M = 0.0005
HOME = np.array([0.42, 0.0, 0.40])
BUTTON = np.array([0.50, 0.10, 0.04])  # the scene's button frame: the centre of its top face
CONTACT_Z = 0.0082  # the grasp point's height above a surface the closed fingertips touch
DEPTHS_M = (0.018, 0.028)  # how far below contact the demonstrator pushed (the flaw)


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


def demonstration(rng, button, depth):
    def near(point, spread):
        return np.asarray(point) + rng.normal(0, spread, 3) * np.array([1, 1, 0.5])

    above = button + np.array([0, 0, 0.10])
    press = button + np.array([0, 0, CONTACT_Z - depth]) + rng.normal(0, 0.0005, 3) * np.array([1, 1, 0])
    phases = [  # (target, mean seconds to reach it, spread)
        (HOME, 0.0, 0.0),
        (HOME, 1.5, 0.3),
        (near(above, 0.003), 3.0, 0.4),
        (above, 1.0, 0.2),  # steady above the button
        (press, 1.6, 0.2),
        (press, 3.0, 0.3),  # hold the press
        (near(above, 0.004), 1.5, 0.2),
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
    dx, dy = stratified(rng, COUNT, -0.05, 0.05), stratified(rng, COUNT, -0.05, 0.05)
    depths = stratified(rng, COUNT, *DEPTHS_M)
    for i in range(COUNT):
        button = BUTTON + np.array([dx[i], dy[i], 0.0])
        times, path = demonstration(rng, button, depths[i])
        stem = OUT / f"demo_{i + 1:02d}"
        with open(f"{stem}.csv", "w") as f:
            f.write("t,x,y,z\n")
            for t, (x, y, z) in zip(times, path):
                f.write(f"{t:.2f},{x:.5f},{y:.5f},{z:.5f}\n")
        pos = ", ".join(f"{v:.4f}" for v in button)
        Path(f"{stem}.frames.yaml").write_text(f"frames:\n  button: {{position: [{pos}], yaw: 0.0}}\n")


if __name__ == "__main__":
    main()
