#!/usr/bin/env python
"""Lagrangian mechanics benchmark (issue 4): derivation + compilation, then speed of the result.

    python benchmarks/bench_mechanics.py            # about a minute
    python benchmarks/bench_mechanics.py --quick    # smoke run; figures not representative

(a) Cold start, each in a fresh process (median of ``--cold`` processes): SymPy import and the
    double pendulum's derivation from K and U; generating and compiling its Numba functions
    (acceleration, analytic Jacobian, energy: ``LagrangianSystem.problem``); the first RK4 run,
    which compiles the foundation's time loop around them. Target: derivation + compilation of
    the double pendulum ≤ 3 s.
(b) Throughput of the derived code: 10,000 double pendulums, RK4, dt = 1e-3, 1000 steps, with
    the generated Numba acceleration and with the generated NumPy (batch) functions, next to the
    hand-written closed-form double pendulum of ``bench_integrators.py`` in the same run.

Figures, not tests; timing helpers (medians, CPU share of other processes) are shared with
``bench_integrators.py``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import sympy

sys.path.insert(0, str(Path(__file__).parent))
import bench_integrators as common
import visviva as vv
from visviva.mechanics import classic

COLD = r"""
import time
started = time.perf_counter()
import sympy
import visviva as vv
from visviva.mechanics import classic
imported = time.perf_counter()
system = classic.double_pendulum()
derived = time.perf_counter()
problem = system.problem([2.0, 1.0], [0.0, 0.0])
compiled = time.perf_counter()
vv.solve(problem, "rk4", dt=1e-3, until=0.01)
ran = time.perf_counter()
print(imported - started, derived - imported, compiled - derived, ran - compiled)
"""


def cold_start(processes: int) -> None:
    common.heading("(a) cold start: double pendulum from K and U, fresh processes")
    samples = []
    for _ in range(processes):
        output = subprocess.run(
            [sys.executable, "-c", COLD], capture_output=True, text=True, check=True
        ).stdout
        samples.append([float(x) for x in output.split()])
    columns = list(zip(*samples, strict=True))
    labels = (
        "import sympy + visviva.mechanics",
        "derive Euler–Lagrange equations (SymPy)",
        "generate + compile acceleration, Jacobian, energy",
        "first RK4 run (compiles the time loop)",
    )
    rows = [
        [label, common.fmt_time(statistics.median(c))]
        for label, c in zip(labels, columns, strict=True)
    ]
    derive_compile = statistics.median([s[1] + s[2] for s in samples])
    rows.append(["derivation + compilation (target ≤ 3 s)", common.fmt_time(derive_compile)])
    common.print_table(["step", f"median of {processes}"], rows)


def throughput(systems: int, steps: int, repeats: int) -> None:
    common.heading(f"(b) {systems} double pendulums, RK4, dt = 1e-3, {steps} steps")
    system = classic.double_pendulum()
    rng = np.random.default_rng(0)
    q0, v0 = rng.uniform(-2, 2, (systems, 2)), rng.uniform(-1, 1, (systems, 2))
    until = steps * 1e-3
    y0 = np.concatenate([q0, v0], axis=1)
    cases = {
        "visviva, generated Numba": system.problem(q0, v0, backend="numba"),
        "visviva, generated NumPy": system.problem(q0, v0, backend="numpy"),
        "visviva, hand-written Numba f": vv.ode.FirstOrderProblem(common.pendulum_numba, y0),
        "hand-written Numba kernel": None,
    }
    rows = []
    for label, problem in cases.items():
        if problem is None:
            call = lambda: common.handwritten_numba_rk4(y0, 0.0, 1e-3, steps)  # noqa: E731
        else:
            call = lambda p=problem: vv.solve(p, "rk4", dt=1e-3, until=until, record_every=steps)  # noqa: E731
        timing = common.measure(call, repeats, label)
        rate = systems * steps / timing.median
        rows.append([label, common.fmt_time(timing.median), common.sci(rate)])
    common.print_table(["code", "time", "system-steps/s"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--cold", type=int, default=5, help="fresh processes for (a)")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(
        "visviva mechanics benchmark"
        + ("  [--quick: figures not representative]" if args.quick else "")
    )
    print(f"date:     {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}")
    print(f"CPU:      {common.cpu_description()}, {os.cpu_count()} logical cores")
    versions = f"numpy {np.__version__}, sympy {sympy.__version__}, numba {numba.__version__}"
    print(f"Python {platform.python_version()}, {versions}")
    print(f"visviva:  {vv.__version__} ({common.source_state()})")
    print(f"load average at start: {common.load_average()}")
    cold_start(1 if args.quick else args.cold)
    throughput(
        200 if args.quick else 10_000,
        100 if args.quick else 1000,
        1 if args.quick else args.repeats,
    )


if __name__ == "__main__":
    main()
