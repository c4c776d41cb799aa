"""Video benchmark: 20,000 spheres × 300 frames rendered to a 960×540 mp4 (and a GIF).

The recording is a swirl of particles (each circling the vertical axis at its own rate and
bobbing up and down) inside a 4 m × 2 m × 4 m box, without radii, so they are drawn at the
default radius (1 % of the scene's diagonal). It prints, for one run on this machine:
  (a) the time per frame of the drawing alone (no encoding), after compilation;
  (b) render_video to mp4 end to end (drawing + ffmpeg/libx264 in its own process);
  (c) render_video to GIF at 480×270 for a third of the frames; and the file sizes.

    python benchmarks/bench_video.py            # about half a minute
    python benchmarks/bench_video.py --quick    # 2,000 spheres, 60 frames

These are figures, not tests.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

import visviva as vv
from visviva.viz.frame import FramePainter, drawn_bounds
from visviva.viz.video import Camera, render_video


def swirl(count: int, frames: int, fps: float = 30.0) -> vv.Recording:
    """``count`` particles circling the Y axis (angular speed ∝ r^-1/2) and bobbing [m]."""
    rng = np.random.default_rng(7)
    t = np.arange(frames) / fps
    radius = 2.0 * np.sqrt(rng.uniform(0.02, 1.0, count))
    angle = rng.uniform(0.0, 2.0 * np.pi, count)[None, :] + t[:, None] * 1.5 / np.sqrt(radius)
    height = rng.uniform(0.3, 1.8, count)
    phase = rng.uniform(0.0, 2.0 * np.pi, count)
    points = np.empty((frames, count, 3))
    points[..., 0] = radius * np.cos(angle)
    points[..., 2] = radius * np.sin(angle)
    points[..., 1] = height + 0.2 * np.sin(2.0 * t[:, None] + phase)
    return vv.Recording(t, {"particle_position": points}, units={"particle_position": "m"})


def timed(label: str, call):
    started = time.perf_counter()
    result = call()
    seconds = time.perf_counter() - started
    print(f"  {label:50s} {seconds:8.2f} s")
    return result, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    count, frames = (2_000, 60) if args.quick else (20_000, 300)
    size = (960, 540)
    print("visviva video benchmark")
    print(f"date: {datetime.now(UTC).isoformat(timespec='seconds')}")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(f"visviva {vv.__version__}, numpy {np.__version__}")
    print(f"workload: {count} spheres, {frames} frames at 30 fps, {size[0]}×{size[1]}\n")
    recording = swirl(count, frames)
    geometry = recording.geometry()

    camera = Camera.framing(drawn_bounds(geometry), aspect=size[0] / size[1])
    painter, _ = timed(
        "set-up: kernels (cached), sky and ground",
        lambda: FramePainter(geometry, size, camera, recording.time),
    )
    painter.paint(0, 0.0)
    _, seconds = timed(
        f"drawing only, {frames} frames",
        lambda: [painter.paint(k, float(recording.time[k])) for k in range(frames)],
    )
    print(f"  {'  per frame':50s} {1e3 * seconds / frames:8.1f} ms")

    with tempfile.TemporaryDirectory() as folder:
        mp4 = Path(folder) / "swirl.mp4"
        _, seconds = timed(
            f"render_video → mp4 {size[0]}×{size[1]}",
            lambda: render_video(recording, mp4, size=size, progress=False),
        )
        print(f"  {'  per frame':50s} {1e3 * seconds / frames:8.1f} ms")
        gif = Path(folder) / "swirl.gif"
        short = vv.Recording(
            recording.time[: frames // 3], {"particle_position": geometry.points[: frames // 3]}
        )
        timed(
            f"render_video → gif 480×270, {frames // 3} frames",
            lambda: render_video(short, gif, size=(480, 270), progress=False),
        )
        sizes = [f"{p.suffix[1:]} {p.stat().st_size / 2**20:.1f} MiB" for p in (mp4, gif)]
        print("\n  " + ", ".join(sizes))


if __name__ == "__main__":
    main()
