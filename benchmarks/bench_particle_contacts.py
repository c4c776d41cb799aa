#!/usr/bin/env python
"""Particle–particle collision benchmark: visviva's contact stage against SciPy + NumPy.

Run ``python benchmarks/bench_particle_contacts.py`` (a few minutes on 2 cores) or add
``--quick`` for a smoke run (under a minute) whose figures mean little.

Two clouds of N equal spheres (r = 1 cm, 1 g; N = 100,000, ``--quick``: 10,000), seeded, rows
in random order, no colliders and no gravity (the peer has neither):

* **pile**: a dense pile, a cubic lattice of touching spheres (six contacts a sphere, three
  per sphere counted once), each falling at g·h with ±1 mm/s on top, as in a settled pile
  whose contacts hold it up every step;
* **gas**: a loose gas, uniform in a cube at a volume fraction of 10 %, moving at 1 m/s
  (each component), so that a step holds fresh collisions.

One step of the contact stage, as a simulation takes it: detection (``|x_i − x_j| < 2r`` plus
the speculative margin of the step's motion), ``K`` = 10 sweeps of impulses (restitution 0.5,
friction 0.3) and ``K`` sweeps of projections:

* visviva: ``ParticleContacts.resolve`` (the neighbour grid, the compiled sweeps), without
  the last step's impulses (no warm start), so that every repeat does the same work;
* SciPy + NumPy: ``cKDTree(x).query_pairs(2r + margin, output_type="ndarray")``, then the same
  per-contact arithmetic (normals, targets, accumulated and clamped normal and friction
  impulses, projections) vectorized over all contacts at once, each sweep's changes summed per
  sphere with ``np.bincount``. NumPy cannot sweep the contacts one after another (that is
  Gauss–Seidel, a sequential loop), so it does Jacobi sweeps: the same work per sweep, but
  weaker convergence per sweep — the figure compares the cost of a sweep, not the quality of
  the answer (the residual overlap of each is printed).

(c) The solve on one core against the slabs swept on two (the measurement behind
``PARALLEL_MIN_CONTACTS``).

Every figure is the median of ``--repeats`` calls after one warm-up call. Not a test: it
prints figures, and exits 1 only if a sanity check fails (momentum kept to round-off).
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
from visviva.collision import particle_contacts
from visviva.collision.particle_contacts import SPECULATIVE, ParticleContacts
from visviva.ode.workspace import Workspace

SEED = 20261125
RADIUS = 0.01  # m
MASS = 1e-3  # kg
H = 1e-3  # s
SWEEPS = 10
RESTITUTION, FRICTION = 0.5, 0.3


def pile(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A cubic lattice of touching spheres (gaps of 10⁻⁶ r), each falling at the speed gravity
    gives in a step (9.81 mm/s) give or take 1 mm/s: every neighbour a contact."""
    rng = np.random.default_rng(SEED)
    side = int(np.ceil(n ** (1.0 / 3.0)))
    axis = np.arange(side) * 2.0 * RADIUS * (1.0 + 5e-7)
    points = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)[:n]
    velocities = rng.uniform(-1e-3, 1e-3, (n, 3)) + np.array([0.0, -9.81 * H, 0.0])
    order = rng.permutation(n)
    return points[order], velocities[order]


def gas(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Uniform in a cube at 10 % volume fraction, velocities N(0, 1 m/s) per component."""
    rng = np.random.default_rng(SEED + 1)
    side = (n * 4.0 / 3.0 * np.pi * RADIUS**3 / 0.1) ** (1.0 / 3.0)
    return rng.uniform(0.0, side, (n, 3)), rng.normal(0.0, 1.0, (n, 3))


def visviva_step(x: np.ndarray, v: np.ndarray):
    """One stage pass on copies (the step's start one step of ``v`` back)."""
    stage = ParticleContacts(
        np.full(x.shape[0], 1.0 / MASS), restitution=RESTITUTION, friction=FRICTION,
        iterations=SWEEPS, gravity=(0.0, 0.0, 0.0),
    )  # fmt: skip

    work = Workspace()  # the run's storage, as a simulation keeps it between steps

    def call() -> tuple[np.ndarray, np.ndarray, int]:
        xs, vs = x.copy(), v.copy()
        radius = np.full(x.shape[0], RADIUS)
        stage.resolve(x - H * v, xs, vs, radius, ALIVE[x.shape[0]], H, work=work)
        return xs, vs, int(stage.solved(work).first.shape[0])

    return call


ALIVE: dict[int, np.ndarray] = {}


def numpy_step(x: np.ndarray, v: np.ndarray):
    """cKDTree pairs, then Jacobi sweeps of the same impulses and projections in NumPy."""
    n = x.shape[0]
    w = np.full(n, 1.0 / MASS)

    def call() -> tuple[np.ndarray, np.ndarray, int]:
        xs, vs = x.copy(), v.copy()
        move = float(np.sqrt((H * H * (v * v).sum(axis=1)).max()))
        slack = SPECULATIVE * 2.0 * RADIUS + min(2.0 * move, 4.0 * RADIUS)
        pairs = cKDTree(xs).query_pairs(2.0 * RADIUS + slack, output_type="ndarray")
        i, j = pairs[:, 0], pairs[:, 1]
        d = xs[i] - xs[j]
        dist = np.sqrt((d * d).sum(axis=1))
        normal = d / dist[:, None]
        gap = dist - 2.0 * RADIUS
        vn = ((vs[i] - vs[j]) * normal).sum(axis=1)
        colliding = (gap <= 0.0) | (gap + vn * H < 0.0)
        target = np.where(colliding, np.where(vn < 0.0, -RESTITUTION * vn, 0.0), -gap / H)
        both = w[i] + w[j]
        meff = 1.0 / both
        ln, lt = np.zeros(len(i)), np.zeros((len(i), 3))
        for _ in range(SWEEPS):
            rv = vs[i] - vs[j]
            new = np.maximum(ln + meff * (target - (rv * normal).sum(axis=1)), 0.0)
            dn, ln = new - ln, new
            rv = rv + (both * dn)[:, None] * normal
            tangent = rv - (rv * normal).sum(axis=1)[:, None] * normal
            g = lt - meff[:, None] * tangent
            size = np.sqrt((g * g).sum(axis=1))
            cap = FRICTION * ln
            g *= np.where(size > cap, cap / np.maximum(size, 1e-300), 1.0)[:, None]
            impulse = dn[:, None] * normal + g - lt
            lt = g
            for k in range(3):
                vs[:, k] += w * (
                    np.bincount(i, impulse[:, k], n) - np.bincount(j, impulse[:, k], n)
                )
        for _ in range(SWEEPS):
            gap = ((xs[i] - xs[j]) * normal).sum(axis=1) - 2.0 * RADIUS
            push = np.where(gap < 0.0, -gap / both, 0.0)
            for k in range(3):
                step = push * normal[:, k]
                xs[:, k] += w * (np.bincount(i, step, n) - np.bincount(j, step, n))
        return xs, vs, len(i)

    return call


def overlap(x: np.ndarray) -> float:
    """Deepest overlap of the spheres at ``x``, in radii."""
    pairs = cKDTree(x).query_pairs(2.0 * RADIUS, output_type="ndarray")
    if not len(pairs):
        return 0.0
    d = np.sqrt(((x[pairs[:, 0]] - x[pairs[:, 1]]) ** 2).sum(axis=1))
    return float((2.0 * RADIUS - d).max() / RADIUS)


def bench_steps(args: argparse.Namespace, checks: Checks) -> None:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    heading(f"One contact step, {SWEEPS} + {SWEEPS} sweeps, N = {args.size:,} spheres")
    rows = []
    for name, make in (("pile", pile), ("gas", gas)):
        x, v = make(args.size)
        ALIVE[x.shape[0]] = np.ones(x.shape[0], dtype=bool)
        ours = measure(visviva_step(x, v), args.repeats, f"visviva {name}")
        theirs = measure(numpy_step(x, v), args.repeats, f"scipy {name}")
        for label, timing in ((f"visviva ({cores} threads)", ours),
                              ("cKDTree + NumPy (Jacobi)", theirs)):  # fmt: skip
            xs, vs, count = timing.result
            rows.append([
                name, label, f"{count:,}", fmt_time(timing.median),
                f"{overlap(x):.4f} -> {overlap(xs):.4f}", timing.busy,
            ])  # fmt: skip
        rows.append([name, "ratio NumPy / visviva", "", f"{theirs.median / ours.median:.1f}×", "",
                     ""])  # fmt: skip
        xs, vs, _ = ours.result
        p0, p1 = v.sum(axis=0) * MASS, vs.sum(axis=0) * MASS
        checks.check(
            np.abs(p1 - p0).max() <= 1e-12 * MASS * np.abs(v).sum(),
            f"{name}: visviva keeps the momentum to round-off (change {np.abs(p1 - p0).max():.2e})",
        )
    print_table(
        ["cloud", "runner", "contacts", "median", "overlap/r before -> after", "others busy"], rows
    )


def bench_parallel(args: argparse.Namespace) -> None:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    heading(
        f"(c) The solve on one core and on {cores}; now PARALLEL_MIN_CONTACTS = "
        f"{particle_contacts.PARALLEL_MIN_CONTACTS:,}"
    )
    saved = particle_contacts.PARALLEL_MIN_CONTACTS
    rows = []
    try:
        for n in args.threshold_sizes:
            x, v = pile(n)
            ALIVE[n] = np.ones(n, dtype=bool)
            medians = []
            for threshold in (1 << 62, 0):
                particle_contacts.PARALLEL_MIN_CONTACTS = threshold
                timing = measure(visviva_step(x, v), args.repeats, f"solve N = {n}")
                medians.append(timing.median)
            count = timing.result[2]
            rows.append([f"{n:,}", f"{count:,}", fmt_time(medians[0]), fmt_time(medians[1]),
                         f"{medians[0] / medians[1]:.2f}"])  # fmt: skip
    finally:
        particle_contacts.PARALLEL_MIN_CONTACTS = saved
    print_table(["N", "contacts", "step, solve serial", f"solve on {cores}", "ratio"], rows)


def print_header(args: argparse.Namespace) -> None:
    print("visviva particle-contact benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
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
    parser.add_argument("--quick", action="store_true", help="small sizes; figures mean little")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=None, help="re-measurements when contended")
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (3 if args.quick else 7)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    PATIENCE["retries"] = max(0, 0 if args.quick else 2 if args.retries is None else args.retries)
    args.size = 10_000 if args.quick else 100_000
    args.threshold_sizes = (10_000,) if args.quick else (10_000, 30_000, 100_000, 300_000)
    # Compile (or load from the cache) every kernel before the header and the timings.
    x, v = gas(2000)
    ALIVE[2000] = np.ones(2000, dtype=bool)
    visviva_step(x, v)()
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    bench_steps(args, checks)
    bench_parallel(args)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
