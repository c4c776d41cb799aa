#!/usr/bin/env python
"""Web viewer benchmark: file size, write time and load time in headless Chromium.

Run ``python benchmarks/bench_viewer.py`` (about 30 s; ``--repeats`` to change the number of
page loads). It needs Debian's Chromium at ``/usr/bin/chromium`` and prints figures; the only
checks are sanity conditions (the page reached ``ready`` with no console error and made no
request beyond the file), and it exits with status 1 if one fails.

Workloads:

* ``cloth``: a 64×64 grid (4096 vertices, 7938 triangles) waving for 300 frames at 30 Hz,
  without radii (vertices drawn as small spheres) — the size the viewer is designed to open
  in under 2 s;
* ``falling``: three points and two edges, 50 frames — the fixed cost of the page (three.js
  bundle, WebGL context, first frame).

Figures per workload: the HTML size, the time ``write_viewer`` takes, the load time from
navigation start to ``window.visviva.ready`` (the first frame finished on the GPU, by a fence,
from the page's own ``performance.now()``), the wall time of Playwright's ``goto`` until ``ready``
is seen, and the time to draw one frame while paused (software WebGL here: SwiftShader).
Each load is a fresh page; medians over ``--repeats`` loads after one warm-up load.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import Browser, sync_playwright

import visviva as vv
from visviva.viz.viewer import write_viewer

CHROMIUM = Path("/usr/bin/chromium")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
]
#: Milliseconds per paused frame: setFrame(k), then one pixel read back (which waits for the
#: frame to be drawn), averaged over 10 frames.
DRAW_TIME_JS = """() => {
  visviva.pause();
  const gl = document.getElementById("view").getContext("webgl2");
  const pixel = new Uint8Array(4);
  const started = performance.now();
  for (let k = 1; k <= 10; k++) {
    visviva.setFrame(k % visviva.frames);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
  }
  return (performance.now() - started) / 10;
}"""


def waving_cloth(n: int = 64, frames: int = 300) -> vv.Recording:
    """An n×n grid, 1 m square, a travelling wave of 0.1 m amplitude in y, at 30 Hz."""
    u, w = np.meshgrid(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n), indexing="ij")
    t = np.arange(frames) / 30.0
    points = np.empty((frames, n * n, 3))
    points[:, :, 0] = u.ravel()
    points[:, :, 1] = 1.0 + 0.1 * np.sin(2.0 * np.pi * (u.ravel()[None, :] - t[:, None]))
    points[:, :, 2] = w.ravel()
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + n], 1), np.stack([a + 1, a + n + 1, a + n], 1)])
    units = {"particle_position": "m"}
    return vv.Recording(t, {"particle_position": points}, static={"faces": faces}, units=units)


def falling() -> vv.Recording:
    """Three points dropped from 2 m, 50 frames at 25 Hz, with two edges."""
    t = np.arange(50) / 25.0
    points = np.zeros((50, 3, 3))
    points[:, :, 0] = [0.0, 1.0, 2.0]
    points[:, :, 1] = 2.0 - 4.9 * t[:, None] ** 2
    return vv.Recording(
        t,
        {"particle_position": points},
        static={"particle_radius": np.full(3, 0.1), "edges": np.array([[0, 1]])},
    )


def load_once(browser: Browser, path: Path) -> tuple[float, float, float, list[str]]:
    """One fresh page: (ready [s from navigation start], wall [s], draw [s/frame], problems)."""
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    problems: list[str] = []
    page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(str(e)))
    page.on(
        "request",
        lambda r: problems.append(f"request {r.url}") if r.url != path.as_uri() else None,
    )
    started = time.perf_counter()
    page.goto(path.as_uri(), wait_until="commit")
    page.wait_for_function("window.visviva && window.visviva.ready === true", polling=20)
    wall = time.perf_counter() - started
    ready = page.evaluate("visviva.readyTime") / 1000.0
    draw = page.evaluate(DRAW_TIME_JS) / 1000.0
    page.close()
    return ready, wall, draw, problems


def cpu_model() -> str:
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        return platform.processor()
    names = [line.split(":", 1)[1].strip() for line in lines if line.startswith("model name")]
    return names[0] if names else platform.processor()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="page loads per workload")
    args = parser.parse_args(argv)
    if not CHROMIUM.is_file():
        print(f"needs Debian's chromium at {CHROMIUM}: apt-get install -y chromium")
        return 1
    version = subprocess.run(
        [str(CHROMIUM), "--version"], capture_output=True, text=True, check=False
    ).stdout.strip()
    print(f"# visviva web viewer — {time.strftime('%Y-%m-%d')}, {cpu_model()}")
    print(f"# {os.cpu_count()} CPUs, Python {platform.python_version()}, {version}")
    print(f"# load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print()
    print(
        "| workload | HTML size | write | ready (median, min–max) | goto→ready wall | draw/frame |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    failed = False
    with tempfile.TemporaryDirectory() as folder, sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=FLAGS)
        for name, recording in (("cloth", waving_cloth()), ("falling", falling())):
            path = Path(folder) / f"{name}.html"
            started = time.perf_counter()
            write_viewer(recording, path)
            write = time.perf_counter() - started
            load_once(browser, path)  # warm-up: disk cache, shader compilation paths
            runs = [load_once(browser, path) for _ in range(args.repeats)]
            for run in runs:
                if run[3]:
                    print(f"FAILED {name}: {run[3]}", file=sys.stderr)
                    failed = True
            ready = [run[0] for run in runs]
            print(
                f"| {name} | {path.stat().st_size / 1e6:.2f} MB | {write:.2f} s "
                f"| {statistics.median(ready):.2f} s ({min(ready):.2f}–{max(ready):.2f}) "
                f"| {statistics.median(run[1] for run in runs):.2f} s "
                f"| {1000 * statistics.median(run[2] for run in runs):.0f} ms |"
            )
        browser.close()
    print()
    print(f"# load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
