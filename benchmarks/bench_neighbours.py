#!/usr/bin/env python
"""Neighbour-search benchmark: visviva's hashed grid against SciPy's ``cKDTree``.

Run ``python benchmarks/bench_neighbours.py`` (about a minute on 2 cores) or add ``--quick``
for a smoke run whose figures mean nothing. SciPy is a visviva dependency, so both runners
always run, in the same process.

The cloud, the same for every runner (float64): N points (N = 10,000 and 100,000; ``--quick``:
1,000 and 10,000) uniform in a cube whose side is chosen so that a point has on average
``NEIGHBOURS`` = 15 others within the radius r = 1 m (a boids-like density: side
(N · 4/3 π r³ / 15)^(1/3), 14.1 m at N = 10⁴, 30.3 m at 10⁵), seeded; the rows in random
order, as a simulation's particles are.

(a) Neighbour lists, every point's neighbours within r:

* visviva: ``NeighbourGrid.update(positions)`` then ``grid.neighbours()`` (CSR lists, each
  ascending, without the point itself), on every core and on one thread; and the update
  alone (it runs on one core), the per-step cost a force kernel that loops over cells pays
  before its own work;
* SciPy: ``cKDTree(positions)`` then ``tree.query_ball_point(positions, r, workers=W)`` with
  W = 2 (every core) and 1; it returns a NumPy array of Python lists (unsorted), which is
  timed as it comes: turning it into arrays (``--quick`` shows how long) is left out, to
  SciPy's advantage.

(b) Pairs, every pair i < j within r once:

* visviva: ``update`` then ``grid.pairs()`` (two arrays, lexicographic order);
* SciPy: ``cKDTree(positions)`` then ``tree.query_pairs(r, output_type="ndarray")`` (one
  thread: it has no ``workers``), unordered.

Every figure is the median of ``--repeats`` calls after one warm-up call (which compiles);
the ratios are SciPy's time over visviva's (above 1: visviva is faster), each against the
SciPy runner with the same cores. The cost ratio is the time at the larger N over the time at
the smaller (10 for linear cost). Each run checks that both give the same sets: the lists
point by point, the pairs as sorted arrays (random reals make exact ties at r improbable).

(c) Where two cores pay: ``update`` + ``neighbours()`` with the queries forced onto the serial
and onto the parallel kernels at N = 250 … 64,000 (``--quick``: 250 and 8,000), the
measurement behind ``PARALLEL_MIN_POINTS`` (the rebuild always runs on one core; see
``visviva.geometry.neighbour_cells`` for why).

This is not a test: it prints figures and exits 1 only if a sanity check fails.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
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
from visviva.geometry import neighbour_grid
from visviva.geometry.neighbour_grid import NeighbourGrid

SEED = 20261125
RADIUS = 1.0  # m
NEIGHBOURS = 15.0  # mean points within RADIUS of a point


def cloud(n: int, seed: int = SEED) -> np.ndarray:
    """``n`` points uniform in a cube at the benchmark's density, rows in random order."""
    side = (n * (4.0 / 3.0) * np.pi * RADIUS**3 / NEIGHBOURS) ** (1.0 / 3.0)
    return np.random.default_rng(seed).uniform(0.0, side, size=(n, 3))


class Threads:
    """Run with ``count`` Numba threads, then restore the previous count."""

    def __init__(self, count: int) -> None:
        self.count = count

    def __enter__(self) -> None:
        self.previous = numba.get_num_threads()
        numba.set_num_threads(self.count)

    def __exit__(self, *exc: object) -> None:
        numba.set_num_threads(self.previous)


def lists_of(start: np.ndarray, index: np.ndarray) -> list[list[int]]:
    return [index[start[i] : start[i + 1]].tolist() for i in range(start.shape[0] - 1)]


def same_lists(start: np.ndarray, index: np.ndarray, tree_lists: np.ndarray) -> bool:
    """Whether the CSR lists hold cKDTree's sets (which include the point itself)."""
    expected = [sorted(j for j in items if j != i) for i, items in enumerate(tree_lists)]
    return lists_of(start, index) == expected


def same_pairs(first: np.ndarray, second: np.ndarray, tree_pairs: np.ndarray) -> bool:
    if tree_pairs.shape[0] != first.shape[0]:
        return False
    order = np.lexsort((tree_pairs[:, 1], tree_pairs[:, 0]))
    return bool(
        np.array_equal(tree_pairs[order, 0], first) and np.array_equal(tree_pairs[order, 1], second)
    )


# --------------------------------------------------------------------------------------------
# (a) and (b)
# --------------------------------------------------------------------------------------------


def plan_for(part: str, points: np.ndarray, cores: int) -> list[tuple[str, int, Callable]]:
    """The runners of part ``part`` on ``points``: (label, threads, call)."""
    grid = NeighbourGrid(RADIUS)

    def visviva_lists() -> tuple[np.ndarray, np.ndarray]:
        grid.update(points)
        return grid.neighbours()

    def visviva_pairs() -> tuple[np.ndarray, np.ndarray]:
        grid.update(points)
        return grid.pairs()

    def update_only() -> None:
        grid.update(points)

    def tree_lists(workers: int) -> Callable[[], np.ndarray]:
        return lambda: cKDTree(points).query_ball_point(points, RADIUS, workers=workers)

    def tree_pairs() -> np.ndarray:
        return cKDTree(points).query_pairs(RADIUS, output_type="ndarray")

    if part == "a":
        return [
            (f"visviva update + neighbours(), {cores} threads", cores, visviva_lists),
            ("visviva update + neighbours(), 1 thread", 1, visviva_lists),
            ("visviva update alone (always 1 thread)", cores, update_only),
            (f"cKDTree + query_ball_point, workers={cores}", cores, tree_lists(cores)),
            ("cKDTree + query_ball_point, workers=1", 1, tree_lists(1)),
        ]
    return [
        (f"visviva update + pairs(), {cores} threads", cores, visviva_pairs),
        ("visviva update + pairs(), 1 thread", 1, visviva_pairs),
        ("cKDTree + query_pairs (1 thread)", 1, tree_pairs),
    ]


def bench_queries(args: argparse.Namespace, checks: Checks) -> dict[tuple[str, int], float]:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    medians: dict[tuple[str, int], float] = {}
    for part, what in (("a", "neighbour lists"), ("b", "pairs")):
        heading(f"({part}) {what}, r = {RADIUS:g} m, about {NEIGHBOURS:g} neighbours a point")
        rows = []
        for n in args.sizes:
            points = cloud(n)
            plan = plan_for(part, points, cores)
            results = {}
            for label, threads, call in plan:
                with Threads(threads):
                    timing = measure(call, args.repeats, f"{label}, N = {n:,}")
                medians[(label, n)] = timing.median
                results[label] = timing.result
                rows.append([label, f"{n:,}", fmt_time(timing.median), timing.spread, timing.busy])
            if part == "a":
                start, index = results[plan[0][0]]
                tree = results[plan[3][0]]
                checks.check(
                    same_lists(start, index, tree),
                    f"N = {n:,}: visviva's lists are cKDTree's sets "
                    f"({index.size:,} entries, {index.size / n:.1f} a point)",
                )
                with Threads(1):
                    serial = plan[1][2]()
                checks.check(
                    np.array_equal(serial[1], index),
                    f"N = {n:,}: the same lists on 1 and {cores} threads",
                )
                if args.quick:
                    began = time.perf_counter()
                    _ = [np.sort(np.asarray(items, dtype=np.int64)) for items in tree]
                    rows.append(
                        [
                            "  (turning cKDTree's lists into sorted arrays)",
                            f"{n:,}",
                            fmt_time(time.perf_counter() - began),
                            "1 run",
                            "",
                        ]
                    )
            else:
                first, second = results[plan[0][0]]
                checks.check(
                    same_pairs(first, second, results[plan[2][0]]),
                    f"N = {n:,}: visviva's pairs are cKDTree's ({first.size:,} pairs)",
                )
        print_table(["runner", "N", "median", "min–max (runs)", "others busy"], rows)
    return medians


def summarise(args: argparse.Namespace, medians: dict[tuple[str, int], float]) -> None:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    heading("Ratios: cKDTree's time over visviva's, and cost from the smaller N to the larger")
    small, large = args.sizes[0], args.sizes[-1]
    comparisons = [
        (
            f"lists, {cores} threads/workers",
            f"visviva update + neighbours(), {cores} threads",
            f"cKDTree + query_ball_point, workers={cores}",
        ),
        (
            "lists, 1 thread/worker",
            "visviva update + neighbours(), 1 thread",
            "cKDTree + query_ball_point, workers=1",
        ),
        (
            f"pairs, visviva on {cores} threads",
            f"visviva update + pairs(), {cores} threads",
            "cKDTree + query_pairs (1 thread)",
        ),
        (
            "pairs, 1 thread each",
            "visviva update + pairs(), 1 thread",
            "cKDTree + query_pairs (1 thread)",
        ),
    ]
    rows = []
    for name, ours, theirs in comparisons:
        cells = [name]
        for n in args.sizes:
            cells.append(f"{medians[(theirs, n)] / medians[(ours, n)]:.1f}×")
        cells.append(f"{medians[(ours, large)] / medians[(ours, small)]:.1f}")
        cells.append(f"{medians[(theirs, large)] / medians[(theirs, small)]:.1f}")
        rows.append(cells)
    update = "visviva update alone (always 1 thread)"
    rows.append(
        [
            "update alone (no peer)",
            *["" for _ in args.sizes],
            f"{medians[(update, large)] / medians[(update, small)]:.1f}",
            "",
        ]
    )
    print_table(
        [
            "comparison",
            *[f"cKDTree/visviva N = {n:,}" for n in args.sizes],
            f"visviva cost {large // small}× N",
            f"cKDTree cost {large // small}× N",
        ],
        rows,
    )


# --------------------------------------------------------------------------------------------
# (c) Serial against parallel kernels
# --------------------------------------------------------------------------------------------


def bench_parallel(args: argparse.Namespace) -> None:
    cores = min(2, numba.config.NUMBA_NUM_THREADS)
    heading(
        f"(c) Serial and parallel queries ({cores} threads); now PARALLEL_MIN_POINTS = "
        f"{neighbour_grid.PARALLEL_MIN_POINTS:,}"
    )
    saved = neighbour_grid.PARALLEL_MIN_POINTS
    rows = []
    try:
        for n in args.threshold_sizes:
            points = cloud(n, SEED + 1)
            grid = NeighbourGrid(RADIUS)

            def both(grid: NeighbourGrid = grid, points: np.ndarray = points) -> None:
                grid.update(points)
                grid.neighbours()

            update = measure(partial(grid.update, points), args.repeats, f"update N = {n}")
            medians, busy = [], []
            for threshold in (10**12, 0):  # serial queries, then parallel ones
                neighbour_grid.PARALLEL_MIN_POINTS = threshold
                timing = measure(both, args.repeats, f"update + neighbours N = {n}")
                medians.append(timing.median)
                busy.append(timing.busy)
            rows.append(
                [
                    f"{n:,}",
                    fmt_time(update.median),
                    fmt_time(medians[0]),
                    fmt_time(medians[1]),
                    f"{medians[0] / medians[1]:.2f}",
                    " / ".join(busy),
                ]
            )
    finally:
        neighbour_grid.PARALLEL_MIN_POINTS = saved
    print_table(
        [
            "N",
            "update (1 core)",
            "update + neighbours(), serial",
            f"parallel ({cores} threads)",
            "serial / parallel",
            "others busy",
        ],
        rows,
    )


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace) -> None:
    print("visviva neighbour-search benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
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
    parser.add_argument("--quick", action="store_true", help="small sizes; figures mean nothing")
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
    args.sizes = (1_000, 10_000) if args.quick else (10_000, 100_000)
    args.threshold_sizes = (
        (250, 8_000) if args.quick else (250, 500, 1_000, 2_000, 4_000, 8_000, 16_000, 64_000)
    )
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    # Compile (or load from the cache) every kernel before the header and the timings.
    small = NeighbourGrid(RADIUS)
    for n in (10, neighbour_grid.PARALLEL_MIN_POINTS):
        small.update(cloud(n))
        small.neighbours()
        small.pairs()
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    medians = bench_queries(args, checks)
    summarise(args, medians)
    bench_parallel(args)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
