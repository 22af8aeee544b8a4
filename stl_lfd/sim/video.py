"""Watching a rollout: headless videos from the scene camera (frames rendered by the backend's
world, written by imageio), and real-time pacing for a GUI.

`.mp4` is encoded with the ffmpeg binary that the `imageio-ffmpeg` wheel ships; `.gif` with
Pillow. One frame is taken at t = 0 and then every 1/fps seconds of simulated time; each
frame shows its time (which also keeps GIF writers from merging frames that look alike).
"""

from __future__ import annotations

import time as clock
from pathlib import Path
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import ExecutionError
from stl_lfd.sim.backend import Observer
from stl_lfd.sim.scene import Camera

VIDEO_SUFFIXES = (".mp4", ".gif")


def frame_count(duration: float, fps: float) -> int:
    """Frames of a video of `duration` seconds: one at 0 and one every 1/fps after it."""
    return int(np.floor(duration * fps + 1e-9)) + 1


def stamp_time(image: np.ndarray, time: float) -> np.ndarray:
    """`image` with the simulated time written in its top-left corner."""
    from PIL import Image, ImageDraw

    picture = Image.fromarray(image)
    ImageDraw.Draw(picture).text((8, 6), f"t = {time:5.2f} s", fill=(20, 20, 20))
    return np.asarray(picture)


class VideoRecorder:
    """An observer for a backend that films (`Capabilities.films`): it films the world into `path`.

    Args:
        path: `.mp4` or `.gif` file to write.
        camera: the viewpoint and size; `camera.fps` frames per simulated second.
        on_frame: called with the number of frames written so far (for progress bars).
    """

    def __init__(self, path: Path, camera: Camera, on_frame: Callable[[int], None] | None = None) -> None:
        import imageio.v2 as imageio

        path = Path(path)
        if path.suffix.lower() not in VIDEO_SUFFIXES:
            raise ExecutionError(f"{path}: video must be .mp4 or .gif")
        self.path = path
        self.camera = camera
        self.on_frame = on_frame
        self.frames = 0
        # libx264 needs even sizes; a macro block of 2 avoids imageio resizing to multiples of 16
        options = dict(fps=camera.fps, macro_block_size=2) if path.suffix.lower() == ".mp4" else dict(duration=1000.0 / camera.fps, loop=0)
        try:
            self.writer = imageio.get_writer(path, **options)
        except Exception as error:  # the writer plugins raise many kinds of errors
            raise ExecutionError(f"{path}: cannot write video ({error})") from None

    def __call__(self, time: float, world: Any) -> None:
        if time + 1e-9 < self.frames / self.camera.fps:
            return
        self.writer.append_data(stamp_time(world.render(self.camera), time))
        self.frames += 1
        if self.on_frame is not None:
            self.on_frame(self.frames)

    def close(self) -> None:
        self.writer.close()


def pace_real_time() -> Observer:
    """An observer that slows the simulation down to wall-clock time (for the GUI)."""
    start: list[float] = []

    def observe(time: float, world: Any) -> None:
        if not start:
            start.append(clock.perf_counter() - time)
        delay = start[0] + time - clock.perf_counter()
        if delay > 0:
            clock.sleep(delay)

    return observe
