#!/usr/bin/env python
"""Boids benchmark: one flocking step of visviva's stage against SciPy ``cKDTree`` + NumPy.

Run ``python benchmarks/bench_boids.py`` (a minute or two on 2 cores) or add ``--quick`` for a
smoke run (fewer repeats, no re-measuring when the machine is busy; the same sizes). SciPy is
a visviva dependency, so both runners always run, in the same process.

The flock, the same for every runner (float64): N boids (N = 10,000 and 100,000) uniform in a
cube whose side gives a boid on average ``NEIGHBOURS`` = 15 others within the radius r = 1 m
(the density of ``bench_neighbours.py``), rows in random order, each velocity component drawn
from a normal distribution of 1 m/s; the rules: separation s = 0.4 m, field of view 270°,
V = 2 m/s, A = 4 m/s², weights 3, 1, 0.7 [1/s] and a goal (weight 0.3/s); no colliders, no
leaders. One step of h = 0.01 s:

* visviva: ``Boids.apply(before, after, h, work)``, the stage as the pipeline calls it: copy of the
  state, grid rebuild on the live boids, the steering kernel on every core, the velocity
  update (truncated to V) — the whole per-step cost of flocking;
* SciPy + NumPy: ``cKDTree(x).query_pairs(r, output_type="ndarray")`` (one thread: it has no
  ``workers``), both directions of each pair, the field-of-view test, the sums per boid by
  ``np.bincount``, then the same steering and update as array expressions.

Each run checks that both give the same velocities (to 1e-9 m/s: the sums run in different
orders). Every figure is the median of ``--repeats`` calls after one warm-up call (which
compiles); the ratio is the peer's time over visviva's, and the cost ratio the time at 10⁵
over the time at 10⁴ (10 for linear cost). Targets (issue 13): ≤ 20 ms per step at 10⁴ on 2
cores, ≥ 3× the peer, a cost ratio between 8 and 12.

This is not a test: it prints figures and exits 1 only if a sanity check fails.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import sys
import time
from collections.abc import Sequence
from functools import partial

import numba
import numpy as np
import scipy
from scipy.spatial import cKDTree

import visviva as vv
from bench_integrators import (
    PATIENCE,
    Checks,
    cpu_description,
    finish,
    fmt_time,
    heading,
    load_average,
    measure,
    print_table,
    source_state,
)
from visviva.ode.state import Layout, PartView, State
from visviva.ode.workspace import Workspace
from visviva.particles.boids import MAX_CROWDING, Boids

SEED = 20261125
RADIUS = 1.0  # m
NEIGHBOURS = 15.0  # mean boids within RADIUS of a boid
H = 0.01  # s
RULES = dict(
    radius=RADIUS,
    separation=0.4,
    fov_deg=270.0,
    max_speed=2.0,
    max_acceleration=4.0,
    separation_weight=3.0,
    alignment_weight=1.0,
    cohesion_weight=0.7,
    goal=(50.0, 10.0, -20.0),
    goal_weight=0.3,
)


def flock(n: int, seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """Positions [m] and velocities [m/s] of ``n`` boids at the benchmark's density."""
    side = (n * (4.0 / 3.0) * math.pi * RADIUS**3 / NEIGHBOURS) ** (1.0 / 3.0)
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, side, size=(n, 3)), rng.normal(0.0, 1.0, size=(n, 3))


def state_of(x: np.ndarray, v: np.ndarray) -> State:
    """A pipeline state holding the flock (every boid alive)."""
    layout = Layout(
        True,
        (
            PartView("particle_position", 0, shape=x.shape),
            PartView("particle_velocity", 1, shape=v.shape),
        ),
    )
    alive = np.ones(x.shape[0], dtype=bool)
    return State(0.0, (x.ravel().copy(), v.ravel().copy()), layout, {"particle_alive": alive})


def _norm(a: np.ndarray) -> np.ndarray:
    return np.hypot(a[..., 0], np.hypot(a[..., 1], a[..., 2]))


def _steer(direction: np.ndarray, v: np.ndarray, vmax: float) -> np.ndarray:
    """Rows ``V d/|d| − v``, zero where ``d`` is zero."""
    length = _norm(direction)
    safe = np.where(length > 0.0, length, 1.0)
    return np.where((length > 0.0)[:, None], vmax * direction / safe[:, None] - v, 0.0)


def _truncate(a: np.ndarray, limit: np.ndarray | float) -> np.ndarray:
    length = _norm(a)
    scale = np.where(length > limit, limit / np.where(length > 0.0, length, 1.0), 1.0)
    return a * scale[:, None]


def numpy_step(x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The same step with cKDTree pairs and NumPy arrays: the new velocities ``(N, 3)``."""
    n = x.shape[0]
    vmax, amax, s = RULES["max_speed"], RULES["max_acceleration"], RULES["separation"]
    v = _truncate(v, vmax)
    pairs = cKDTree(x).query_pairs(RADIUS, output_type="ndarray")
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    j = np.concatenate([pairs[:, 1], pairs[:, 0]])
    d = x[j] - x[i]
    d2 = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2]
    keep = d2 <= RADIUS * RADIUS  # the grid's test, exactly (query_pairs' differs by ulps)
    speed = _norm(v)
    u = v / np.where(speed > 0.0, speed, 1.0)[:, None]
    cos_half = math.cos(math.radians(0.5 * RULES["fov_deg"]))
    dot = d[:, 0] * u[i, 0] + d[:, 1] * u[i, 1] + d[:, 2] * u[i, 2]
    keep &= ~((speed[i] > 0.0) & (dot < cos_half * np.sqrt(d2)))
    i, j, d, d2 = i[keep], j[keep], d[keep], d2[keep]

    def sums(values: np.ndarray, who: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(who, values[:, k], minlength=n) for k in range(3)], axis=1)

    mates = np.bincount(i, minlength=n)
    close = (d2 < s * s) & (d2 > 0.0)
    dist = np.sqrt(d2[close])
    push = (np.minimum(s / dist, MAX_CROWDING) - 1.0) / dist
    crowd = -sums(d[close] * push[:, None], i[close])
    some = (mates > 0)[:, None]
    f = np.where(
        some, RULES["separation_weight"] * _norm(crowd)[:, None] * _steer(crowd, v, vmax), 0
    )
    f += np.where(some, RULES["alignment_weight"] * _steer(sums(v[j], i), v, vmax), 0.0)
    f += np.where(some, RULES["cohesion_weight"] * _steer(sums(d, i), v, vmax), 0.0)
    f += RULES["goal_weight"] * _steer(np.asarray(RULES["goal"]) - x, v, vmax)
    w = v + H * _truncate(f, amax)
    return _truncate(w, vmax)


def bench(args: argparse.Namespace, checks: Checks) -> dict[tuple[str, int], float]:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    heading(f"One step of h = {H:g} s, r = {RADIUS:g} m, about {NEIGHBOURS:g} boids within r")
    medians: dict[tuple[str, int], float] = {}
    rows = []
    for n in args.sizes:
        x, v = flock(n)
        stage = Boids(np.arange(n), **RULES)  # type: ignore[arg-type]
        before = state_of(x, v)
        after = state_of(x, v)
        work = Workspace()  # the run's storage, as a simulation keeps it between steps
        step = partial(stage.apply, before, after, H, work)
        ours = measure(step, args.repeats, f"visviva N = {n:,}")
        theirs = measure(partial(numpy_step, x, v), args.repeats, f"cKDTree+NumPy N = {n:,}")
        medians[("visviva", n)] = ours.median
        medians[("peer", n)] = theirs.median
        rows.append(
            [
                f"visviva Boids stage, {cores} threads",
                f"{n:,}",
                fmt_time(ours.median),
                ours.spread,
                ours.busy,
            ]
        )
        rows.append(
            [
                "cKDTree.query_pairs + NumPy (1 thread)",
                f"{n:,}",
                fmt_time(theirs.median),
                theirs.spread,
                theirs.busy,
            ]
        )
        ours_v = ours.result["particle_velocity"]
        gap = float(np.abs(ours_v - theirs.result).max())
        checks.check(gap <= 1e-9, f"N = {n:,}: the same velocities (largest difference {gap:.1e})")
    print_table(["runner", "N", "median", "min–max (runs)", "others busy"], rows)
    return medians


def summarise(args: argparse.Namespace, medians: dict[tuple[str, int], float]) -> None:
    heading("Ratios and targets (issue 13)")
    small, large = args.sizes[0], args.sizes[-1]
    ours = medians[("visviva", small)]

    def meets(ok: bool) -> str:
        return "yes" if ok else "NO"

    ratio = medians[("peer", small)] / ours
    cost = medians[("visviva", large)] / ours
    peer_cost = medians[("peer", large)] / medians[("peer", small)]
    rows = [
        [f"time per step at N = {small:,}", fmt_time(ours), "≤ 20 ms", meets(ours <= 0.020)],
        [f"cKDTree+NumPy / visviva at N = {small:,}", f"{ratio:.1f}×", "≥ 3×", meets(ratio >= 3)],
        [
            f"visviva cost {small:,} → {large:,}",
            f"{cost:.1f}",
            "8 – 12",
            meets(8.0 <= cost <= 12.0),
        ],
        [f"peer cost {small:,} → {large:,}", f"{peer_cost:.1f}", "", ""],
        [
            f"cKDTree+NumPy / visviva at N = {large:,}",
            f"{medians[('peer', large)] / medians[('visviva', large)]:.1f}×",
            "",
            "",
        ],
    ]
    print_table(["figure", "measured", "target", "met"], rows)


def print_header(args: argparse.Namespace) -> None:
    print("visviva boids benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / scipy:     {np.__version__} / {scipy.__version__}")
    print(f"numba:             {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    print(f"Numba threads:     {numba.config.NUMBA_NUM_THREADS}, layer {numba.threading_layer()}")
    print(f"timing:            median of {args.repeats} runs after a warm-up run")
    print(f"load average:      {load_average()} at start")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="few repeats; figures are rough")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=None, help="re-measurements when contended")
    parser.add_argument(
        "--quiet-wait",
        type=float,
        default=10.0,
        help="before a retry, wait up to this many seconds for the machine to be idle (default 10)",
    )
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (3 if args.quick else 7)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    if args.retries is None:
        args.retries = 0 if args.quick else 2
    args.sizes = (10_000, 100_000)
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    # Compile (or load from the cache) both kernels, serial and parallel, before timing.
    for n in (100, 1000):
        x, v = flock(n)
        stage = Boids(np.arange(n), **RULES)  # type: ignore[arg-type]
        stage.apply(state_of(x, v), state_of(x, v), H, Workspace())
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    medians = bench(args, checks)
    summarise(args, medians)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
