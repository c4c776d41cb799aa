"""Outputs benchmark (issue 3): recording and exporting 500 frames of 20,000 particles.

Times, in one run on this machine:
  (a) ``visviva run`` of a 20k-particle scene recording 500 frames (simulation + streaming
      HDF5 writes), and writing the same frames with h5py in one call, as the floor;
  (b) exporting that recording to USD (usdc), glb and the single-file HTML viewer;
  (c) the file sizes.

    python benchmarks/bench_outputs.py            # about a minute
    python benchmarks/bench_outputs.py --quick    # 2,000 particles, 100 frames

These are figures, not tests.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
import warnings
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

import visviva as vv
from visviva.io.timeline import frames_at_rate


def timed(label: str, call):
    started = time.perf_counter()
    result = call()
    seconds = time.perf_counter() - started
    print(f"  {label:46s} {seconds:8.2f} s")
    return result, seconds


def size(path: Path) -> str:
    if path.is_dir():
        total = sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    else:
        total = path.stat().st_size
    return f"{total / 2**20:.1f} MiB"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    count, frames = (2_000, 100) if args.quick else (20_000, 500)
    print("visviva outputs benchmark")
    print(f"date: {datetime.now(UTC).isoformat(timespec='seconds')}")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(f"visviva {vv.__version__}, numpy {np.__version__}")
    print(f"workload: {count} particles, {frames} recorded frames\n")

    builder = vv.SceneBuilder(name="benchmark spray")
    dt = 1e-3
    builder.set_integration(
        method="symplectic_euler", dt=dt, duration=(frames - 1) * 4 * dt, record_every=4
    )
    builder.add_particle_cloud(count=count, velocity=[0.0, 3.0, 0.0], velocity_jitter=1.0)
    model = builder.build()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        print("(a) recording")
        timed("visviva run (simulate + stream to HDF5)", lambda: vv.run_scene(model, out))
        recording = vv.io.load_recording(out / "recording.h5")
        assert recording.frames == frames, recording.frames

        def floor() -> None:
            import h5py

            with h5py.File(Path(tmp) / "floor.h5", "w") as file:
                file.create_dataset("particle_position", data=recording["particle_position"])
                file.create_dataset("particle_velocity", data=recording["particle_velocity"])

        timed("h5py, the same arrays in one call (floor)", floor)
        print(f"  recording.h5: {size(out / 'recording.h5')}")

        print("(b) exports (USD and glb: every recorded frame; the viewer: its default rate)")
        from visviva.io.export import export_recording
        from visviva.viz.viewer import default_fps, write_viewer

        every_frame = 1.0 / (4 * dt)  # the recorded rate [frames/s]
        targets = {
            "USD (usdc)": Path(tmp) / "scene.usdc",
            "glb": Path(tmp) / "scene.glb",
        }
        for label, path in targets.items():
            timed(
                f"{label}, {frames} frames",
                lambda path=path: export_recording(recording, path, fps=every_frame),
            )
        html = Path(tmp) / "viewer.html"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the viewer says it lowered its rate to fit
            fps = default_fps(recording)
        shown = frames_at_rate(recording.time, fps).size
        timed(
            f"HTML viewer, {shown} frames at {fps:.3g} fps",
            lambda: write_viewer(recording, html, fps=fps),
        )
        print("(c) sizes")
        for label, path in [*targets.items(), ("HTML viewer", html)]:
            print(f"  {label:46s} {size(path):>10s}")


if __name__ == "__main__":
    main()
