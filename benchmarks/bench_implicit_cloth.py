#!/usr/bin/env python
"""Implicit cloth benchmark: backward Euler at h = 1/60 s by projected Newton, visviva's CG
against SciPy's.

Run ``python benchmarks/bench_implicit_cloth.py`` (a few minutes on 2 cores) or add ``--quick``
for a smoke run whose figures mean nothing.

The scene, the same for every runner, built through visviva's public API (float64):

* an N × N cloth (N = 64, 128; ``--quick``: 16, 24) spanning 1 m × 1 m in the x–z plane at
  height y = 1 m (``add_cloth``: origin (0, 1, 0), along x, across z); point (i, j) has index
  j·N + i;
* areal density 0.1 kg/m²; structural springs k = 1000 N/m, shear 100 N/m, bend 1 N/m, each
  with damping 0.01 N·s/m along it, resting at their initial lengths;
* the two corners of the first row (points 0 and N − 1) pinned;
* gravity (0, −9.81, 0) m/s²; steps of h = 1/60 s by ``vv.integrators.ProjectedNewton``:
  backward Euler solved by Newton's method on the incremental potential, with the stiffness
  projected to be definite where it must be (``projection="adaptive"``), a backtracking line
  search, and each Newton system A d = −g, A = M − h D − h² K (3×3 blocks), solved by
  conjugate gradients preconditioned by A's inverted 3×3 diagonal blocks (block Jacobi) to a
  relative residual of ``cg_rtol`` = 1e-2.

Runners (each from the same cloth at rest: one warm-up step, which compiles, then the timed
steps, 30 by default and 5 with ``--quick``, each ``sim.step()`` timed on its own):

* visviva: ``ProjectedNewton()`` with its defaults; its linear solve is ``block_cg``, Numba
  kernels running in parallel over block rows on every core;
* SciPy CG: the same integrator with only its linear solve replaced (``ScipyCGNewton``). It
  assembles A's blocks with the same Numba kernel as visviva (``_newton_blocks``), converts the
  BSR matrix to CSR, inverts A's 3×3 diagonal blocks with ``np.linalg.inv`` and solves with
  ``scipy.sparse.linalg.cg`` (x0 = 0, ``rtol=cg_rtol``, ``atol=0``, ``maxiter`` =
  ``cg_max_iterations``), the inverted blocks as its preconditioner. The stopping rule is the
  same (‖b − A x‖ < rtol ‖b‖). visviva's CG also stops at a direction of non-positive
  curvature and says so, which makes the adaptive projection solve again with the definite
  stiffness; the SciPy runner detects that in its matrix product (one extra dot product per
  iteration) and stops likewise, so the two runners take the same Newton path (up to
  round-off: see the sanity checks) and differ only in the linear solver. SciPy's sparse
  products run on one thread.

Figures per N and runner: wall time per step (mean = total ÷ steps, and the median), Newton
iterations, linear solves, CG iterations and line-search halvings per step (work counts from
``sim.system.counters``), CG iterations per Newton iteration, and the wall time spent inside
the integrator's ``_solve`` per step (assembling A, preconditioner set-up and CG). Then the
ratios SciPy ÷ visviva for the whole step and for the linear solve, against the targets: at
most 16 ms per step at N = 64 and 60 ms at N = 128 (the mean), and SciPy ÷ visviva ≥ 3 for
the whole step; and the ratio of the linear solve's time per CG iteration, which does not
depend on how many iterations each runner took.

Sanity checks: no NaN; after the warm-up step (one step from the same start) the two runners'
positions agree within 1e-6 m; and after all the steps within 5 cm. The two runners solve the
same equations to the same tolerances, and their CG iterates differ by round-off only, but
round-off is enough to send the cloth down different paths: within the first ten steps it
buckles, its incremental potential has more than one minimum, and a different Newton iteration
count or line-search decision in one step picks another. Measured at N = 64 (default
tolerances): the positions agree to 1e-16 m for two steps, 1e-7 m after six, then the runners
part (steps 7–8, one Newton iteration more in one of them) and differ by up to 1.1 cm (step
16), 2.6 mm after 31 steps. With the tolerances tightened (Newton's rtol 1e-9, atol 1e-10 m/s,
``cg_rtol`` 1e-10) they still part at step 7 (126 against 96 Newton iterations in that step)
and differ by up to 1.2 cm: the spread is the problem's, not the tolerances'. So the check
at the end only guards against a runner solving a different problem (the cloth falls about
1 m meanwhile); the strict one is after the first step. This is not a test: it prints figures
and exits 1 only if a sanity check fails.

Shared machines: visviva's CG enters five parallel regions per iteration, and while other
processes keep a core busy each may wait for a time slice. Measured here with another
process's test suite running, visviva's steps took 15.7 s instead of 0.6 s at N = 64 and 14 s
instead of 1.7 s at N = 128. The "others' CPU" column shows whether a
figure was taken so (each run first waits up to ``--quiet-wait`` seconds for an idle machine).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import visviva as vv
from bench_integrators import (
    CONTENDED,
    CONTENTION_WARNING,
    Checks,
    Contention,
    cpu_description,
    finish,
    heading,
    load_average,
    print_table,
    wait_for_quiet,
)
from visviva.integrators.projected_newton import _newton_blocks, _same_blocks

# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------

GRAVITY = (0.0, -9.81, 0.0)  # m/s²
STEP = 1.0 / 60.0  # s
DENSITY = 0.1  # kg/m²
STRETCH = 1000.0  # N/m, structural springs
SHEAR = 100.0  # N/m, diagonal springs
BEND = 1.0  # N/m, springs between points two apart
DAMPING = 0.01  # N·s/m, along every spring
HEIGHT = 1.0  # m

SIZES = (64, 128)
QUICK_SIZES = (16, 24)
STEPS = 30  # timed steps per run, after one warm-up step
QUICK_STEPS = 5

#: The issue's targets: mean wall time per step [s] by N, and SciPy ÷ visviva per step.
TARGET_STEP = {64: 16e-3, 128: 60e-3}
TARGET_RATIO = 3.0
#: Largest allowed difference between the runners' positions [m]: after the warm-up step, and
#: after all the steps (see the module docstring for why the second is loose).
AGREEMENT_FIRST = 1e-6
AGREEMENT_END = 0.05


def cloth_scene(n: int) -> Any:
    """The scene at N = n, built through the public API (the method is chosen per runner)."""
    builder = vv.SceneBuilder(name=f"implicit cloth {n}x{n}")
    builder.set_world(gravity=GRAVITY)
    builder.set_integration(method="symplectic_euler", dt=STEP, duration=100.0)
    builder.add_cloth(
        (n, n),
        stretch=STRETCH,
        shear=SHEAR,
        bend=BEND,
        damping=DAMPING,
        density=DENSITY,
        origin=(0.0, HEIGHT, 0.0),
        along=(1.0, 0.0, 0.0),
        across=(0.0, 0.0, 1.0),
        pinned=[0, n - 1],
    )
    return builder.build()


# --------------------------------------------------------------------------------------------
# The two integrators: visviva's, and the same with SciPy's CG
# --------------------------------------------------------------------------------------------


class TimedNewton(vv.integrators.ProjectedNewton):
    """``ProjectedNewton`` with its defaults, adding up the wall time [s] of its linear solves
    (two ``perf_counter`` calls per solve, nothing else)."""

    def __init__(self) -> None:
        super().__init__()
        self.solve_seconds = 0.0

    def _solve(self, *args: Any) -> tuple[np.ndarray, bool]:
        start = time.perf_counter()
        result = self._direction(*args)
        self.solve_seconds += time.perf_counter() - start
        return result

    def _direction(self, *args: Any) -> tuple[np.ndarray, bool]:
        """The Newton direction and whether A looked positive definite (visviva's solve)."""
        return vv.integrators.ProjectedNewton._solve(self, *args)


class ScipyCGNewton(TimedNewton):
    """The same integrator, its Newton systems solved by ``scipy.sparse.linalg.cg``."""

    def __init__(self) -> None:
        super().__init__()
        self.setup_seconds = 0.0  # of solve_seconds: CSR conversion and block inversion [s]

    def _direction(
        self,
        system: Any,
        mass: np.ndarray,
        stiffness: Any,
        damping: Any,
        h: float,
        rhs: np.ndarray,
        normals: np.ndarray | None = None,
        extra: np.ndarray | None = None,
    ) -> tuple[np.ndarray, bool]:
        """Solve (M − h D − h² K) d = rhs as visviva's ``_solve`` does, with SciPy's CG."""
        if normals is not None or extra is not None or not _same_blocks(stiffness, damping):
            raise NotImplementedError("only a free cloth's 3×3-block Newton matrix is handled")
        # The Newton matrix's blocks, exactly as in ProjectedNewton._solve.
        data = np.empty_like(stiffness.data)
        damping_data = stiffness.data[:0] if damping is None else damping.data
        indptr, indices = stiffness.indptr, stiffness.indices
        _newton_blocks(indptr, indices, stiffness.data, damping_data, mass.reshape(-1, 3), h, data)
        start = time.perf_counter()
        matrix = sp.bsr_matrix((data, indices, indptr), shape=stiffness.shape).tocsr()
        preconditioner = block_jacobi(indptr, indices, data)
        self.setup_seconds += time.perf_counter() - start
        system.counters.linear_solves += 1
        direction, iterations, positive = scipy_cg(
            matrix, preconditioner, rhs, self.cg_rtol, self.cg_max_iterations
        )
        system.counters.krylov_iterations += iterations
        return direction.reshape(rhs.shape), positive


def block_jacobi(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray) -> Any:
    """The inverse of the matrix's 3×3 diagonal blocks, as a block-diagonal SciPy operator.

    ``indptr``, ``indices``, ``data``: a BSR matrix with a diagonal block in every block row.
    """
    count = indptr.size - 1
    block_row = np.repeat(np.arange(count), np.diff(indptr))
    diagonal = data[indices == block_row]
    if diagonal.shape[0] != count:
        raise ValueError("every block row needs its diagonal block")
    inverse = np.linalg.inv(diagonal)
    rows = np.arange(count + 1)
    blocks = sp.bsr_matrix((inverse, rows[:-1], rows), shape=(3 * count, 3 * count))
    return spla.aslinearoperator(blocks)


class NegativeCurvature(Exception):
    """Raised by the matrix product when CG's direction p has pᵀAp ≤ 0."""


def scipy_cg(
    matrix: Any, preconditioner: Any, rhs: np.ndarray, rtol: float, max_iterations: int
) -> tuple[np.ndarray, int, bool]:
    """``scipy.sparse.linalg.cg`` on ``matrix`` from x0 = 0, stopped like ``block_cg``.

    Returns ``(x, iterations, positive)``. SciPy multiplies by A once per iteration, by CG's
    direction p; where pᵀAp ≤ 0 the product raises, and the iterate of the iteration before is
    returned with ``positive`` false, as ``block_cg`` does (iterations then counts the one
    stopped, as there).
    """

    def product(p: np.ndarray) -> np.ndarray:
        q = matrix @ p
        # p = 0 only if SciPy ever multiplies its zero start: no curvature to judge there.
        if not float(p @ q) > 0.0 and p.any():
            raise NegativeCurvature
        return q

    progress = {"iterations": 0, "iterate": np.zeros_like(rhs)}

    def callback(x: np.ndarray) -> None:
        # SciPy hands over its iterate itself, updated in place afterwards: at a raise from
        # ``product`` it still holds the iteration before's.
        progress["iterations"] += 1
        progress["iterate"] = x

    operator = spla.LinearOperator(matrix.shape, matvec=product, dtype=np.float64)
    try:
        x, _ = spla.cg(
            operator,
            rhs,
            x0=np.zeros_like(rhs),
            rtol=rtol,
            atol=0.0,
            maxiter=max_iterations,
            M=preconditioner,
            callback=callback,
        )
    except NegativeCurvature:
        return np.array(progress["iterate"]), progress["iterations"] + 1, False
    return x, progress["iterations"], True


# --------------------------------------------------------------------------------------------
# Running and measuring
# --------------------------------------------------------------------------------------------

VISVIVA = "visviva"
SCIPY = "SciPy CG"
RUNNERS: dict[str, Callable[[], TimedNewton]] = {VISVIVA: TimedNewton, SCIPY: ScipyCGNewton}


@dataclass
class Run:
    """One runner's timed steps at one N."""

    label: str
    n: int
    times: list[float]  # wall time of each timed step [s]
    first: float  # the warm-up step [s]
    solve_seconds: float  # inside the linear solve over the timed steps [s]
    setup_seconds: float  # of which CSR conversion and block inversion (SciPy only) [s]
    work: dict[str, int]  # counters over the timed steps
    start: np.ndarray  # (N², 3) positions [m] after the warm-up step
    positions: np.ndarray  # (N², 3) m after the warm-up and timed steps
    others: float | None  # other processes' share of the machine meanwhile

    @property
    def steps(self) -> int:
        return len(self.times)

    @property
    def mean(self) -> float:
        """Wall time per step [s]: total ÷ steps."""
        return sum(self.times) / self.steps

    @property
    def solve_mean(self) -> float:
        """Wall time inside the linear solve per step [s]."""
        return self.solve_seconds / self.steps

    def per_step(self, counter: str) -> float:
        return self.work[counter] / self.steps

    @property
    def solve_per_iteration(self) -> float:
        """Wall time inside the linear solve per CG iteration [s]."""
        return self.solve_seconds / max(1, self.work["krylov_iterations"])


def run_once(label: str, n: int, steps: int, quiet_wait: float) -> Run:
    """One warm-up step, then ``steps`` timed steps of a fresh cloth."""
    method = RUNNERS[label]()
    simulation = vv.Simulation(cloth_scene(n), method=method)
    start = time.perf_counter()
    simulation.step()
    first = time.perf_counter() - start
    positions_after_first = np.array(simulation.state["particle_position"])
    counters = simulation.system.counters
    before = counters.as_dict()
    method.solve_seconds = 0.0
    if isinstance(method, ScipyCGNewton):
        method.setup_seconds = 0.0
    wait_for_quiet(quiet_wait)
    meter = Contention()
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        simulation.step()
        times.append(time.perf_counter() - start)
    others = meter.others()
    after = counters.as_dict()
    return Run(
        label,
        n,
        times,
        first,
        method.solve_seconds,
        getattr(method, "setup_seconds", 0.0),
        {key: after[key] - before[key] for key in after},
        positions_after_first,
        np.array(simulation.state["particle_position"]),
        others,
    )


def run(label: str, n: int, steps: int, args: argparse.Namespace) -> Run:
    """``run_once``, again (up to ``--retries`` times) while other processes were busy; the
    fastest attempt is kept (every attempt does the same work from the same start)."""
    attempts = [run_once(label, n, steps, args.quiet_wait)]
    while (attempts[-1].others or 0.0) > CONTENTION_WARNING and len(attempts) <= args.retries:
        attempts.append(run_once(label, n, steps, args.quiet_wait))
    best = min(attempts, key=lambda attempt: attempt.mean)
    if (best.others or 0.0) > CONTENTION_WARNING:
        CONTENDED.append(
            f"{label}, N={n}: other processes used {100.0 * best.others:.0f}% of the machine"
            f" (fastest of {len(attempts)} attempts)"
        )
    return best


def milliseconds(seconds: float) -> str:
    return f"{seconds * 1e3:.1f}"


def busy(others: float | None) -> str:
    return "?" if others is None else f"{100.0 * others:.0f}%"


def bench_runs(args: argparse.Namespace) -> dict[tuple[str, int], Run]:
    """Every runner at every N; prints the per-runner table."""
    heading(
        f"(a) Implicit cloth, h = 1/60 s, {args.steps} timed steps after 1 warm-up step:"
        f" N = {', '.join(map(str, args.sizes))}"
    )
    runs = {}
    rows = []
    for n in args.sizes:
        for label in RUNNERS:
            result = run(label, n, args.steps, args)
            runs[label, n] = result
            print(f"  {label}, N = {n}: {sum(result.times):.2f} s of timed steps", flush=True)
            newton = result.work["newton_iterations"]
            krylov = result.work["krylov_iterations"]
            rows.append(
                [
                    label,
                    str(n),
                    milliseconds(result.mean),
                    milliseconds(statistics.median(result.times)),
                    f"{result.per_step('newton_iterations'):.2f}",
                    f"{result.per_step('linear_solves'):.2f}",
                    f"{result.per_step('krylov_iterations'):.0f}",
                    f"{krylov / newton:.0f}" if newton else "n/a",
                    f"{result.per_step('line_search_steps'):.2f}",
                    milliseconds(result.solve_mean),
                    f"{result.first:.2f} s",
                    busy(result.others),
                ]
            )
    print()
    print_table(
        ["runner", "N", "ms/step", "median", "Newton", "solves", "CG", "CG/Newton"]
        + ["halvings", "solve ms", "warm-up", "others' CPU"],
        rows,
    )
    print(
        "  ms/step: total wall time ÷ steps (median: of the single steps); Newton, solves, CG,"
        " halvings: Newton iterations, linear solves, CG iterations and line-search halvings"
        " per step; CG/Newton: CG iterations per Newton iteration; solve ms: wall time inside"
        " the linear solve (assembling A, preconditioner, CG) per step"
    )
    print(
        "  solves > Newton: where CG meets negative curvature in the exact (unprojected) matrix,"
        " the adaptive projection solves again with the definite one"
    )
    for n in args.sizes:
        scipy_run = runs[SCIPY, n]
        share = scipy_run.setup_seconds / scipy_run.solve_seconds
        print(
            f"  {SCIPY}, N = {n}: BSR → CSR conversion and block inversion take {share:.0%}"
            f" of its linear-solve time"
        )
    print(
        f"  {VISVIVA}: Numba kernels on {numba.get_num_threads()} threads;"
        f" {SCIPY}: SciPy's sparse products on one thread (assembly on"
        f" {numba.get_num_threads()}, the same kernel as visviva's)"
    )
    return runs


def largest_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| over every point and axis [m]."""
    return float(np.abs(a - b).max())


def summarise(args: argparse.Namespace, runs: dict[tuple[str, int], Run], checks: Checks) -> None:
    """The ratios, the targets and the sanity checks."""
    heading("(b) SciPy ÷ visviva, targets and agreement")
    rows = []
    for n in args.sizes:
        ours, theirs = runs[VISVIVA, n], runs[SCIPY, n]
        step_ratio = theirs.mean / ours.mean
        target = TARGET_STEP.get(n)
        rows.append(
            [
                str(n),
                milliseconds(ours.mean),
                "n/a" if target is None else f"≤ {milliseconds(target)}",
                "n/a" if target is None else ("met" if ours.mean <= target else "not met"),
                f"{step_ratio:.2f}×",
                "met" if step_ratio >= TARGET_RATIO else "not met",
                f"{theirs.solve_mean / ours.solve_mean:.2f}×",
                f"{theirs.solve_per_iteration / ours.solve_per_iteration:.2f}×",
                f"{largest_difference(ours.start, theirs.start):.1e}",
                f"{largest_difference(ours.positions, theirs.positions):.1e}",
            ]
        )
    print()
    print_table(
        ["N", "visviva ms/step", "target", "", "SciPy ÷ visviva: step", f"≥ {TARGET_RATIO:g}×"]
        + ["linear solve", "per CG iteration", "max |Δx| [m]: 1 step", f"{1 + args.steps} steps"],
        rows,
    )
    print(
        "  ms/step: total ÷ steps; SciPy ÷ visviva: of the mean wall time per step, of the time"
        " inside the linear solve per step, and of that time per CG iteration; max |Δx|: between"
        " the two runners' positions after the warm-up step and at the end"
    )
    if args.quick:
        print("  --quick: the sizes are not the targets' (64, 128); no target applies")
    print()
    for n in args.sizes:
        ours, theirs = runs[VISVIVA, n], runs[SCIPY, n]
        finite = all(np.isfinite(r.positions).all() for r in (ours, theirs))
        checks.check(finite, f"N={n}: both runners' positions finite")
        first = largest_difference(ours.start, theirs.start)
        checks.check(
            first <= AGREEMENT_FIRST,
            f"N={n}: {VISVIVA} vs {SCIPY} after 1 step: max |Δx| = {first:.1e} m"
            f" (≤ {AGREEMENT_FIRST:g} m)",
        )
        last = largest_difference(ours.positions, theirs.positions)
        sag = HEIGHT - float(ours.positions[:, 1].min())
        checks.check(
            last <= AGREEMENT_END,
            f"N={n}: {VISVIVA} vs {SCIPY} after {1 + args.steps} steps: max |Δx| = {last:.1e} m"
            f" (≤ {AGREEMENT_END:g} m: the cloth buckles, see the module docstring; its lowest"
            f" point fell {sag:.3f} m)",
        )


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace) -> None:
    print("visviva implicit cloth benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    now = datetime.datetime.now().astimezone()
    print(f"date:              {now.isoformat(timespec='seconds')}")
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical, {len(os.sched_getaffinity(0))} usable")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / scipy:     {np.__version__} / {scipy.__version__}")
    print(f"numba:             {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({os.path.dirname(vv.__file__)})")
    print(f"Numba threads:     {numba.get_num_threads()}, layer {numba.threading_layer()}")
    print(
        f"timing:            every step of a run timed; a run whose steps saw other processes"
        f" busy is repeated up to {args.retries} time(s), the fastest kept"
    )
    print(f"load average:      {load_average()} at start")


def warm_up() -> None:
    """Compile (or load from Numba's cache) every kernel the runners use, on a small cloth."""
    for label in RUNNERS:
        vv.Simulation(cloth_scene(8), method=RUNNERS[label]()).step()


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes; figures mean nothing")
    parser.add_argument("--steps", type=int, default=None, help="timed steps per run")
    parser.add_argument("--retries", type=int, default=None, help="re-runs when contended")
    parser.add_argument(
        "--quiet-wait",
        type=float,
        default=10.0,
        help="before each run, wait up to this many seconds for the machine to be idle",
    )
    args = parser.parse_args(argv)
    args.sizes = QUICK_SIZES if args.quick else SIZES
    args.steps = args.steps or (QUICK_STEPS if args.quick else STEPS)
    if args.retries is None:
        args.retries = 0 if args.quick else 1
    warm_up()
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    runs = bench_runs(args)
    summarise(args, runs, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
