"""Signals from outside stlopt must look like a recording of the robot executing the reference
(stl_lfd.sim.plausibility)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from stl_lfd.signals import SignalTable
from stl_lfd.sim import load_scene
from stl_lfd.sim.plausibility import ImplausibleSignals, check_recorded
from stl_lfd.sim.reference import Reference

SCENE = load_scene("free_space")  # workspace x 0.2..0.8, y -0.6..0.6, z 0.1..0.8
TIMES = np.arange(0, 221) / 10  # 22 s at 10 samples/s
REFERENCE = Reference(TIMES, np.tile([0.5, 0.0, 0.4], (TIMES.size, 1)))


def recording(times=TIMES, **columns) -> SignalTable:
    values = {"x": np.full(times.size, 0.5), "y": np.zeros(times.size), "z": np.full(times.size, 0.4), "force": np.zeros(times.size)}
    return SignalTable(times, values | columns, "rec.csv")


def test_a_plausible_recording_passes():
    check_recorded(recording(), REFERENCE, SCENE, 10)
    check_recorded(recording(times=np.arange(0, 22001) / 1000), REFERENCE, SCENE, 10)  # a 1 kHz controller's log
    check_recorded(recording(times=np.arange(0, 241) / 10), REFERENCE, SCENE, 10)  # two seconds of coming to rest


@pytest.mark.parametrize(
    "signals, message",
    [
        (recording(x=np.full(221, 1e300)), r"rec.csv:2: the hand at \(x=1e\+300, y=0, z=0.4\) is more than 0.25 m outside the scene's workspace"),
        (recording(z=np.where(np.arange(221) == 100, 1e308, 0.4)), r"rec.csv:102: the hand at \(x=0.5, y=0, z=1e\+308\)"),
        (recording(y=np.full(221, -0.9)), r"rec.csv:2: the hand at \(x=0.5, y=-0.9, z=0.4\) is more than 0.25 m outside"),
        (recording(times=TIMES * 1000), r"rec.csv: the signals cover 0 to 22000 s, but the rollout lasts 0 to 22 s \(times must be in seconds\)"),
        (recording(times=TIMES[:100]), r"rec.csv: the signals cover 0 to 9.9 s, but the rollout lasts 0 to 22 s$"),
        (recording(times=np.arange(0, 500) / 10), r"rec.csv: the signals cover 0 to 49.9 s, but the rollout lasts 0 to 22 s$"),
        (recording(times=np.arange(0, 23) * 1.0), r"rec.csv: one sample every 1 s, but the rollout is recorded at 100 samples/s"),
        (
            recording(times=np.where(np.arange(221) >= 50, TIMES + 0.03, TIMES)),
            r"rec.csv:52: 0.13 s after the sample before it, but the samples are 0.1 s apart",
        ),
        (recording(times=np.where(np.arange(221) == 50, 4.8, TIMES)), r"rec.csv:53: t = 5.1 s does not come after|rec.csv:52: t = 4.8 s"),
        (recording(force=np.where(np.arange(221) == 7, 5e4, 0.0)), r"rec.csv:9: a force of 5e\+04 N, above the 1000 N a recording may show"),
        (recording(force=np.full(221, -50.0)), r"rec.csv:2: a force of -50 N; `force` is the norm of the contact force, never negative"),
        (recording(tilt=np.full(221, 1e9)), r"rec.csv:2: tilt = 1e\+09, but the hand's tilt \(rad\) lies in \[0, 3.14159\]"),
        (recording(tilt=np.full(221, -3.0)), r"rec.csv:2: tilt = -3, but the hand's tilt"),
        (
            recording(qx=np.zeros(221), qy=np.zeros(221), qz=np.zeros(221), qw=np.full(221, 10.0)),
            r"rec.csv:2: the orientation qx, qy, qz, qw has norm 10; a rotation's quaternion has norm 1",
        ),
    ],
)
def test_an_implausible_recording_is_refused_naming_the_file_and_row(signals, message):
    rate = 100 if "one sample every" in message else 10
    with pytest.raises(ImplausibleSignals, match=message):
        check_recorded(signals, REFERENCE, SCENE, rate)


def test_the_scene_may_raise_the_force_limit():
    strong = replace(SCENE, safety=replace(SCENE.safety, max_force=1e5))
    check_recorded(recording(force=np.full(221, 5e4)), REFERENCE, strong, 10)
    assert "max_force=100000.0" in repr(strong.safety) and "max_force" not in repr(SCENE.safety)  # old runs resume


def test_the_objects_signals_are_checked_too():
    scene = load_scene("pick_insert")
    fine = {"shaft_x": np.full(221, 0.45), "shaft_y": np.full(221, -0.25), "shaft_z": np.full(221, 0.08), "shaft_held": np.zeros(221)}
    check_recorded(recording(**fine), REFERENCE, scene, 10)
    with pytest.raises(ImplausibleSignals, match=r"rec.csv:2: shaft at \(shaft_x=0.45, shaft_y=-0.25, shaft_z=9\) is more than 1 m outside"):
        check_recorded(recording(**fine | {"shaft_z": np.full(221, 9.0)}), REFERENCE, scene, 10)
    with pytest.raises(ImplausibleSignals, match=r"rec.csv:2: shaft_held = 3, but whether the fingers hold shaft \(1 or 0\) lies in \[0, 1\]"):
        check_recorded(recording(**fine | {"shaft_held": np.full(221, 3.0)}), REFERENCE, scene, 10)
    with pytest.raises(ImplausibleSignals, match=r"rec.csv:2: holder_tilt = 2, but holder's tilt \(rad\) lies in \[0, 1.5708\]"):
        check_recorded(recording(**fine | {"holder_tilt": np.full(221, 2.0)}), REFERENCE, scene, 10)
    unit = {f"shaft_{name}": value for name, value in zip(("qx", "qy", "qz", "qw"), (np.zeros(221), np.zeros(221), np.zeros(221), np.ones(221)))}
    check_recorded(recording(**fine | unit), REFERENCE, scene, 10)
    with pytest.raises(ImplausibleSignals, match=r"rec.csv:2: shaft's orientation shaft_qx, shaft_qy, shaft_qz, shaft_qw has norm 2; a rotation's"):
        check_recorded(recording(**fine | unit | {"shaft_qw": np.full(221, 2.0)}), REFERENCE, scene, 10)
