#!/usr/bin/env python
"""Gravitation benchmark: visviva's direct and Barnes–Hut forces against plain Numba and REBOUND.

Run ``python benchmarks/bench_gravity.py`` (about 5 minutes on 2 cores) or add ``--quick`` for a
smoke run whose figures mean nothing. REBOUND is never a visviva dependency; to include it, run
the script from an environment that has both::

    python -m venv --system-site-packages /tmp/peers && /tmp/peers/bin/pip install rebound
    /tmp/peers/bin/python benchmarks/bench_gravity.py

Parts, all on a Plummer sphere in N-body units (G = 1, M = 1, a = 1, softening 0.01):

(a) Direct summation, N = 16,000: one force evaluation through ``gravity_accelerations`` on 1 and
    2 threads, a plain hand-written Numba kernel in the same run, REBOUND's ``"basic"`` gravity
    (one leapfrog step), and one full velocity-Verlet step through ``vv.solve``. Pair
    interactions are counted as N² per evaluation, as NOTES.md does.
(b) Barnes–Hut, N = 16,000: visviva against REBOUND's ``"tree"`` gravity at the same opening
    angle (REBOUND opens a cell of width w seen at distance r from its centre of mass when
    w/r > θ; visviva when the cell's radius about its centre of mass exceeds θ times the
    distance to the group being walked), time per evaluation and error against direct.
(c) Barnes–Hut, N = 10⁶: seconds per evaluation for several θ, with the relative force error
    against direct summation on a random subset of bodies (median and 99th percentile).

Timings are medians of repeated runs after a warm-up; every figure comes with the share of the
CPU other processes used meanwhile (re-measured when above 5%). This is not a test: it prints
figures and exits 1 only if a sanity check fails (visviva and the plain kernel disagree).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from collections.abc import Sequence

import numba
import numpy as np
from numba import njit, prange

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
    sci,
    source_state,
)
from visviva.mechanics import octree
from visviva.mechanics.gravity import direct_accelerations_of, prepare

try:
    import rebound
except ImportError:
    rebound = None

SOFTENING = 0.01
TARGET_PAIRS = 4e9  # pairs/s, N = 16,000, 2 cores, f64 (set on the Zen-5 reference machine)
TARGET_TREE = 2.0  # s per step at N = 10⁶
#: Steps of the full-pipeline run in (a); energy is recorded at the first and last frame.
SOLVE_STEPS = 10


# --------------------------------------------------------------------------------------------
# Peers and references
# --------------------------------------------------------------------------------------------


@njit(parallel=True, fastmath=True)
def plain_numba(x, y, z, m, eps2, ax, ay, az):
    """The textbook kernel: for each body, sum m_j d / (r² + ε²)^{3/2} over all j."""
    n = x.shape[0]
    for i in prange(n):
        sx = 0.0
        sy = 0.0
        sz = 0.0
        for j in range(n):
            dx = x[j] - x[i]
            dy = y[j] - y[i]
            dz = z[j] - z[i]
            r2 = dx * dx + dy * dy + dz * dz + eps2
            w = m[j] / (r2 * np.sqrt(r2))
            sx += w * dx
            sy += w * dy
            sz += w * dz
        ax[i] = sx
        ay[i] = sy
        az[i] = sz


def relative_errors(approximate: np.ndarray, exact: np.ndarray) -> tuple[float, float]:
    """Median and 99th percentile of ``|a − a_exact| / |a_exact|`` over bodies."""
    error = np.linalg.norm(approximate - exact, axis=1) / np.linalg.norm(exact, axis=1)
    return float(np.median(error)), float(np.percentile(error, 99))


def rebound_simulation(cluster: vv.mechanics.Bodies, gravity: str, theta: float = 0.5):
    """A REBOUND simulation of the same bodies, leapfrog, with a negligible step.

    With dt = 1e-30 the drift before the force evaluation moves nothing, so after one step each
    particle's (ax, ay, az) is the force at the given positions.
    """
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.gravity = gravity
    sim.softening = SOFTENING
    sim.integrator = "leapfrog"
    sim.dt = 1e-30
    if gravity == "tree":
        sim.opening_angle2 = theta * theta
        sim.root_size = 4.0 * float(np.abs(cluster.positions).max()) + 1.0
        sim.N_root_x = sim.N_root_y = sim.N_root_z = 1
    for (x, y, z), mass in zip(cluster.positions, cluster.masses, strict=True):
        sim.add(m=float(mass), x=x, y=y, z=z)
    return sim


def rebound_accelerations(sim) -> np.ndarray:
    return np.array([[p.ax, p.ay, p.az] for p in sim.particles])


# --------------------------------------------------------------------------------------------
# (a) Direct summation
# --------------------------------------------------------------------------------------------


def bench_direct(args: argparse.Namespace, checks: Checks) -> None:
    n = args.direct_n
    heading(f"(a) Direct summation, N = {n:,}: one force evaluation")
    cluster = vv.mechanics.plummer_sphere(n, total_mass=1.0, scale_radius=1.0, G=1.0, seed=1)
    x, y, z = (np.ascontiguousarray(cluster.positions[:, k]) for k in range(3))
    m = np.array(cluster.masses)
    pairs = float(n) * n
    rows = []
    results = {}
    for threads in (1, 2):
        numba.set_num_threads(threads)
        timing = measure(
            lambda: vv.mechanics.gravity_accelerations(
                cluster.positions, cluster.masses, G=1.0, softening=SOFTENING
            ),
            args.repeats,
            f"(a) visviva direct, {threads} thread(s)",
        )
        results[("visviva", threads)] = timing.result
        rows.append(direct_row("visviva `gravity_accelerations`", threads, timing, pairs))
        out = np.empty((3, n))
        timing = measure(
            lambda out=out: plain_numba(x, y, z, m, SOFTENING**2, *out) or out.T.copy(),
            args.repeats,
            f"(a) plain Numba, {threads} thread(s)",
        )
        results[("plain", threads)] = timing.result
        rows.append(direct_row("plain Numba kernel (`fastmath=True`)", threads, timing, pairs))
        problem = cluster.problem(softening=SOFTENING)
        timing = measure(
            lambda problem=problem: vv.solve(
                problem,
                "velocity_verlet",
                dt=1e-3,
                until=SOLVE_STEPS * 1e-3,
                record_every=SOLVE_STEPS,
            ),
            max(1, args.repeats // 2),
            f"(a) vv.solve, {threads} thread(s)",
        )
        per_step = timing.median / SOLVE_STEPS
        rows.append(
            [
                f"`vv.solve` velocity Verlet, {SOLVE_STEPS} steps, per step",
                str(threads),
                fmt_time(per_step),
                sci(pairs / per_step),
                timing.spread,
                timing.busy,
            ]
        )
    if rebound is not None:  # the PyPI wheel is built without OpenMP: one thread
        sim = rebound_simulation(cluster, "basic")
        timing = measure(lambda: sim.steps(1), args.repeats, "(a) REBOUND basic")
        rows.append(direct_row("REBOUND `basic`, one leapfrog step", 1, timing, pairs))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    print()
    print_table(["kernel", "threads", "median", "pairs/s", "spread", "others' CPU"], rows)
    print(f"  target: ≥ {sci(TARGET_PAIRS)} pairs/s on 2 cores (set on a Zen-5/AVX-512 machine)")
    scale = np.abs(results[("plain", 2)]).max()
    difference = np.abs(results[("visviva", 2)] - results[("plain", 2)]).max() / scale
    checks.check(difference < 1e-12, f"visviva and plain Numba agree ({difference:.1e} relative)")
    masses = cluster.masses
    force = masses[:, None] * results[("visviva", 2)]
    residual = np.abs(force.sum(axis=0)).max() / np.abs(force).sum()
    print(f"  visviva: |Σ m_i a_i| / Σ |m_i a_i| = {residual:.1e} (momentum by construction)")


def direct_row(label: str, threads: int, timing, pairs: float) -> list[str]:
    return [
        label,
        str(threads),
        fmt_time(timing.median),
        sci(pairs / timing.median),
        timing.spread,
        timing.busy,
    ]


# --------------------------------------------------------------------------------------------
# (b) and (c) Barnes–Hut
# --------------------------------------------------------------------------------------------


def time_tree(cluster: vv.mechanics.Bodies, theta: float, repeats: int, label: str):
    """Timing of one Barnes–Hut evaluation over ``cluster`` (its result: the accelerations)."""
    return measure(
        lambda: vv.mechanics.gravity_accelerations(
            cluster.positions,
            cluster.masses,
            G=1.0,
            softening=SOFTENING,
            method="barnes_hut",
            theta=theta,
        ),
        repeats,
        label,
    )


def bench_tree_small(args: argparse.Namespace) -> None:
    n = args.direct_n
    heading(f"(b) Barnes–Hut, N = {n:,}: visviva and REBOUND, per evaluation")
    cluster = vv.mechanics.plummer_sphere(n, total_mass=1.0, scale_radius=1.0, G=1.0, seed=1)
    exact = vv.mechanics.gravity_accelerations(
        cluster.positions, cluster.masses, G=1.0, softening=SOFTENING
    )
    rows = []
    for theta in args.small_thetas:
        timing = time_tree(cluster, theta, args.repeats, f"(b) visviva tree θ={theta}")
        median, p99 = relative_errors(timing.result, exact)
        rows.append(["visviva `barnes_hut`, 2 threads", f"{theta:g}", fmt_time(timing.median)])
        rows[-1] += [f"{median:.1e}", f"{p99:.1e}", timing.busy]
    for theta in args.small_thetas if rebound is not None else ():
        sim = rebound_simulation(cluster, "tree", theta)
        timing = measure(lambda sim=sim: sim.steps(1), args.repeats, f"(b) REBOUND θ={theta}")
        median, p99 = relative_errors(rebound_accelerations(sim), exact)
        rows.append(["REBOUND `tree`, one leapfrog step, 1 thread", f"{theta:g}"])
        rows[-1] += [fmt_time(timing.median), f"{median:.1e}", f"{p99:.1e}", timing.busy]
    print()
    print_table(["code", "θ", "median", "error median", "error p99", "others' CPU"], rows)
    if rebound is None:
        print("  REBOUND not installed: see the module docstring for how to add it.")


def bench_tree_large(args: argparse.Namespace) -> None:
    n = args.tree_n
    heading(f"(c) Barnes–Hut, N = {n:,}: seconds per evaluation, 2 threads")
    cluster = vv.mechanics.plummer_sphere(n, total_mass=1.0, scale_radius=1.0, G=1.0, seed=2)
    bodies, *_ = prepare(cluster.positions, cluster.masses, 1.0, SOFTENING, "barnes_hut", 0.5)
    sample = np.sort(np.random.default_rng(3).choice(n, size=min(n, args.sample), replace=False))
    exact = np.empty((sample.size, 3))
    started = time.perf_counter()
    direct_accelerations_of(sample, bodies, bodies.mass_scale, exact)  # G = 1
    elapsed = time.perf_counter() - started
    print(f"  reference: direct sums for {sample.size:,} random bodies, {elapsed:.1f} s")
    started = time.perf_counter()
    tree = octree.build_octree(bodies)
    built = time.perf_counter() - started
    print(f"  tree: {tree.start.size:,} cells, depth {tree.depth}, built in {fmt_time(built)}")
    rows = []
    for theta in args.large_thetas:
        timing = time_tree(cluster, theta, max(1, args.repeats // 2), f"(c) visviva tree θ={theta}")
        median, p99 = relative_errors(timing.result[sample], exact)
        meets = (
            "yes" if timing.median <= TARGET_TREE else f"no ({timing.median / TARGET_TREE:.2f}×)"
        )
        rows.append([f"{theta:g}", fmt_time(timing.median), timing.spread, f"{median:.1e}"])
        rows[-1] += [f"{p99:.1e}", meets, timing.busy]
    print()
    print_table(
        ["θ", "median", "min–max (runs)", "error median", "error p99", "≤ 2 s", "others' CPU"],
        rows,
    )


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace) -> None:
    print("visviva gravitation benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    if rebound is None:
        print("REBOUND:           not installed (pip install rebound, in a separate environment)")
    else:
        avx512 = rebound.avx512_available
        print(f"REBOUND:           {rebound.__version__} (AVX-512 kernels: {avx512}; 1 thread)")
    print(f"Numba threads:     {numba.config.NUMBA_NUM_THREADS}, layer {numba.threading_layer()}")
    print(f"load average:      {load_average()} at start")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes; figures mean nothing")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=2, help="re-measurements when contended")
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (2 if args.quick else 5)
    args.direct_n = 2_000 if args.quick else 16_000
    args.tree_n = 50_000 if args.quick else 1_000_000
    args.sample = 2_000 if args.quick else 20_000
    args.small_thetas = (0.5,) if args.quick else (0.3, 0.5, 0.7, 1.0)
    args.large_thetas = (0.5, 0.7) if args.quick else (0.3, 0.5, 0.7, 1.0)
    PATIENCE["retries"] = max(0, args.retries)
    # Compile every kernel before the header's load average and the first timing.
    tiny = vv.mechanics.plummer_sphere(300, total_mass=1.0, scale_radius=1.0, G=1.0)
    for method in ("direct", "barnes_hut"):
        vv.mechanics.gravity_accelerations(tiny.positions, tiny.masses, G=1.0, method=method)
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    bench_direct(args, checks)
    bench_tree_small(args)
    bench_tree_large(args)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
