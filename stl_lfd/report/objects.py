"""The scene's objects in a report: the outlines of the objects the task is about (those of the
scene's frames: the holder and its hole, the rails) and the paths of the objects that move (the
shaft), in the trajectory views; and the figure of the object signals the spec constrains
(`shaft_tilt`, `shaft_depth`, `shaft_offset`, ...; and expressions of them only, such as an
object's offset from its target, `abs(box_x - shelf_x)`) with the spec's thresholds drawn on
them."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

import stl_lfd.rotations as rotations
from stl_lfd.report.run_data import RunData
from stl_lfd.sim.scene import Scene, SceneObject
from stl_lfd.stl import ast
from stl_lfd.stl.thresholds import Threshold, expression_values

OBJECT_COLOR = "0.35"
AXES = {"x": 0, "y": 1, "z": 2}
# The unit of an object signal, by the end of its name (docs/execution.md, signals).
UNITS = {"tilt": "rad", "depth": "m", "offset": "m", "speed": "m/s", "held": "1: held", "x": "m", "y": "m", "z": "m"}


def corners(item: SceneObject) -> np.ndarray:
    """`8 x 3` corners of the box that bounds `item` in its own frame, in the base frame."""
    if item.shape == "box":
        half = np.asarray(item.size, dtype=float)
    elif item.shape == "cylinder":
        half = np.array([item.size[0], item.size[0], item.size[1] / 2])
    else:
        half = np.full(3, item.size[0])
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    turn = rotations.from_euler(*item.orientation)
    return np.asarray(item.position, dtype=float) + rotations.rotate(turn, signs * half)


def outline(points: np.ndarray) -> np.ndarray:
    """The convex hull of `N x 2` points, counter-clockwise."""
    from scipy.spatial import ConvexHull

    return points[ConvexHull(points).vertices]


def fixed_frame_objects(run: RunData) -> list[SceneObject]:
    """The fixed objects the task is about: those of the scene's frames (what a movable object
    is put into or taken from) and those with a clearance (the obstacles), at the run's
    placement; none when the run has several placements (the recorded signals are the worst
    placement's, which they do not name)."""
    return fixed_objects(run.scene, len(run.task.placements))


def fixed_objects(scene: Scene | None, placements: int) -> list[SceneObject]:
    """The fixed objects of `scene`'s frames and those with a clearance, when the run it
    belongs to has one placement."""
    if scene is None or placements > 1:
        return []
    names = {name for frame in scene.frames for name in frame.objects}
    return [item for item in scene.objects if (item.name in names or item.clearance) and item.mass == 0]


def draw_objects(axes, run: RunData, across: str, up: str) -> None:
    """The fixed frame objects' outlines in the view (`across`, `up`), filled light grey."""
    for index, item in enumerate(fixed_frame_objects(run)):
        hull = outline(corners(item)[:, [AXES[across], AXES[up]]])
        label = "objects (outlines)" if index == 0 else None
        axes.add_patch(Polygon(hull, closed=True, facecolor=OBJECT_COLOR, alpha=0.25, edgecolor=OBJECT_COLOR, lw=0.8, zorder=2, label=label))


def object_extents(run: RunData, axis: str) -> list[float]:
    """The lowest and highest `axis` coordinates of the fixed frame objects."""
    points = [corners(item)[:, AXES[axis]] for item in fixed_frame_objects(run)]
    return [float(np.min(values)) for values in points] + [float(np.max(values)) for values in points]


def moving_frames(run: RunData) -> list[str]:
    """The names of the frames that move with an object and whose positions the run recorded."""
    if run.scene is None:
        return []
    return [frame.name for frame in run.scene.moving_frames if set(frame.signals) <= recorded_signals(run)]


def draw_object_paths(axes, run: RunData, across: str, up: str, trials: dict[int, tuple]) -> None:
    """The path of each moving frame's origin (the shaft's centre) in `trials` (trial number ->
    (colour, label)), dotted, with its end as a cross."""
    for name in moving_frames(run):
        for number, (color, label) in trials.items():
            table = run.signals.get(number)
            if table is None:
                continue
            x, y = table.columns[f"{name}_{across}"], table.columns[f"{name}_{up}"]
            axes.plot(x, y, color=color, lw=1.4, ls=":", zorder=3, label=f"{name}, {label}")
            axes.plot(x[-1:], y[-1:], marker="X", ms=8, color=color, mec="white", ls="none", zorder=5)


def constrained_object_signals(run: RunData) -> list[str]:
    """The signals of the scene's frames (`NAME_...`) that the spec compares with a number."""
    if run.scene is None:
        return []
    prefixes = tuple(f"{frame.name}_" for frame in run.scene.frames)
    recorded = recorded_signals(run)
    return [signal for signal in run.thresholds if signal.startswith(prefixes) and signal in recorded]


def constrained_object_expressions(run: RunData) -> list[str]:
    """The expressions the spec compares with a number that read the scene's frames' signals only
    (an object's offset from its target: `abs(box_x - shelf_x)`), all recorded."""
    if run.scene is None:
        return []
    prefixes = tuple(f"{frame.name}_" for frame in run.scene.frames)
    recorded = recorded_signals(run)
    chosen = []
    for text, thresholds in run.expression_thresholds.items():
        names = {node.name for node in ast.post_order(thresholds[0].expression) if type(node) is ast.Signal}
        if all(name.startswith(prefixes) and name in recorded for name in names):
            chosen.append(text)
    return chosen


SIGNAL_WORDS = {
    "depth": "how deep {name}'s lowest point is below {target}'s rim (m)",
    "offset": "{name}'s distance from {target} (m)",
    "height": "how high {name}'s lowest point is above {target}'s origin (m)",
    "dx": "{name}'s offset from {target} along its x axis (m)",
    "dy": "{name}'s offset from {target} along its y axis (m)",
    "tilt": "{name}'s tilt from upright (rad)",
    "speed": "{name}'s speed (m/s)",
    "held": "whether the fingers hold {name} (1 or 0)",
    "x": "{name}'s x (m)",
    "y": "{name}'s y (m)",
    "z": "{name}'s z (m)",
}


def signal_in_words(signal: str, scene) -> str:
    """`box_height, how high box's lowest point is above shelf's origin (m)`, from the scene's
    own names (the frame, and the hole or target it goes into or onto)."""
    frames = [frame for frame in scene.frames if signal.startswith(f"{frame.name}_")]
    frame = max(frames, key=lambda frame: len(frame.name), default=None)  # box_lid_x is box_lid's
    if frame is None:
        return signal
    kind = signal[len(frame.name) + 1 :]
    target = frame.into or frame.onto or "its target"
    words = SIGNAL_WORDS.get(kind)
    return f"{signal}, {words.format(name=frame.name, target=target)}" if words else signal


def recorded_signals(run: RunData) -> set[str]:
    """The signals any of the run's trials recorded."""
    return set().union(*(table.columns for table in run.signals.values()))


def draw_thresholds(axes, thresholds: list[Threshold]) -> None:
    """Each threshold as a dashed horizontal line, labelled as the spec writes it."""
    for threshold in thresholds:
        axes.axhline(threshold.value, color="tab:green", ls="--", lw=1.2, label=f"spec: {threshold}", zorder=1)


def object_signals(run: RunData, per_trial) -> Figure | None:
    """One panel per object signal the spec constrains, every trial's curve (`per_trial`, the
    figures' way of drawing them) and the spec's thresholds; None when it constrains none."""
    signals, expressions = constrained_object_signals(run), constrained_object_expressions(run)
    if not signals and not expressions:
        return None
    count = len(signals) + len(expressions)
    figure = Figure(figsize=(9, 2.2 * count + 0.8), layout="constrained")
    panels = np.atleast_1d(figure.subplots(count, 1, sharex=True))
    for axes, signal in zip(panels, signals):
        curves = {number: (table.times, table.columns[signal]) for number, table in run.signals.items() if signal in table.columns}
        per_trial(axes, run, curves)
        draw_thresholds(axes, run.thresholds[signal])
        unit = UNITS.get(signal.rsplit("_", 1)[-1], "")
        axes.set_ylabel(f"{signal} ({unit})" if unit else signal, fontsize=9)
        axes.legend(loc="upper left", bbox_to_anchor=(1, 1), fontsize=8)
    for axes, text in zip(panels[len(signals) :], expressions):
        thresholds = run.expression_thresholds[text]
        curves = {number: (table.times, expression_values(thresholds[0].expression, table.columns)) for number, table in run.signals.items()}
        per_trial(axes, run, curves)
        draw_thresholds(axes, thresholds)
        axes.set_ylabel(text, fontsize=9)
        axes.legend(loc="upper left", bbox_to_anchor=(1, 1), fontsize=8)
    panels[-1].set_xlabel("t (s)")
    figure.suptitle(f"{run.task.name}: the objects' signals the spec constrains, per trial")
    return figure
