#!/usr/bin/env python
"""Sweep benchmark: a 1000-run ensemble of double pendulums, in batches and run by run.

Run ``python benchmarks/bench_sweeps.py`` (about three minutes on 2 cores) or add ``--quick``
for a smoke run (100 runs, fewer reference runs). The ensemble is
``examples/sweeps/double_pendulum_chaos.toml``: seed 001's double pendulum (1 kg, 1 m) released
at rest with both arms at the same angle, from 0 to 3 rad; RK4 at h = 2 ms for 5 s (2500 steps)
here instead of the example's 10 s; summaries only (no recordings), as a sweep of a thousand
runs is used. Every runner writes the sweep's files (a summary and run.json per run, the
results table, plots and index page) and is timed from the call to its return, pre-checks and
process or cluster start included:

* visviva, batches on the default process pool (2 workers): the runner's own choice;
* visviva, batches on a Dask LocalCluster (2 workers, ``dask_executor``);
* visviva, every run alone on the process pool (``batch=False``): the "N processes" the batches
  replace, timed on the first ``--alone`` runs and given per run;
* SciPy's ``solve_ivp`` (RK45, rtol 1e-9, atol 1e-12 — what a user would loop over), on the same
  equations (visviva's compiled acceleration), one run after another in this process, timed on
  the first ``--alone`` runs: no files, so a lower bound of a script doing the same sweep.

It checks that the runs done alone give the batches' figures bit for bit (final state, energy
error, steps) and that SciPy's final states agree with the batches' where the motion is not
chaotic (releases below 1 rad, to 1e-5 rad). This is not a test: it prints figures and exits 1
only if a check fails.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

import visviva as vv
from bench_integrators import Checks, cpu_description, finish, heading, load_average, print_table
from bench_integrators import source_state as visviva_source
from visviva.model.build import build_model
from visviva.model.scene import Scene
from visviva.sweeps import dask_executor

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "sweeps" / "double_pendulum_chaos.toml"
DURATION = 5.0  # s
FINAL = ("final.generalized_position[0]", "final.generalized_position[1]")


def sweep_file(directory: Path, runs: int) -> Path:
    """The example with ``runs`` releases and 5 s runs, as JSON in ``directory``."""
    data = tomllib.loads(EXAMPLE.read_text())
    data["scene"]["integration"]["duration"] = DURATION
    for parameter in data["parameters"]:
        parameter["range"] = [0.0, 3.0, runs]
    path = directory / f"chaos{runs}.json"
    path.write_text(json.dumps(data))
    return path


def timed(call) -> tuple[float, object]:
    started = time.perf_counter()
    result = call()
    return time.perf_counter() - started, result


def scipy_runs(releases: np.ndarray) -> tuple[float, np.ndarray]:
    """``solve_ivp`` on each release; the time and the final angles ``(runs, 2)``."""
    from scipy.integrate import solve_ivp

    scene = {
        "integration": {"method": "rk4", "dt": 0.002, "duration": DURATION},
        "entities": [{"type": "system", "system": "double-pendulum"}],
    }
    acceleration = build_model(Scene.model_validate(scene)).systems[0].problem.force.func

    def rate(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(4)
        out[:2] = y[2:]
        acceleration(t, y[:2], y[2:], out[2:])
        return out

    rate(0.0, np.zeros(4))  # compiled before the clock starts
    finals = []
    started = time.perf_counter()
    for angle in releases:
        y0 = np.array([angle, angle, 0.0, 0.0])
        solution = solve_ivp(rate, (0.0, DURATION), y0, method="RK45", rtol=1e-9, atol=1e-12)
        finals.append(solution.y[:2, -1])
    return time.perf_counter() - started, np.array(finals)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke run: 100 runs")
    parser.add_argument("--runs", type=int, default=1000, help="runs of the ensemble")
    parser.add_argument("--alone", type=int, default=40, help="runs timed run by run")
    args = parser.parse_args(argv)
    runs, alone = (100, 10) if args.quick else (args.runs, args.alone)
    started = time.perf_counter()
    checks = Checks()
    print("visviva sweep benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(f"CPU:          {cpu_description()}")
    print(f"visviva:      {vv.__version__} ({visviva_source()})")
    print(f"load average: {load_average()} at start")
    print(f"ensemble:     {runs} double pendulums, RK4 h = 2 ms, {DURATION:g} s (2500 steps)")

    root = Path(tempfile.mkdtemp(prefix="bench-sweeps-"))
    try:
        path = sweep_file(root, runs)
        # The first sweep in this process compiles the equations and the batched loops; a
        # user's first sweep pays it once too. Warm it up on a small sweep.
        vv.sweep(sweep_file(root, 4), root / "warm", executor="serial")

        heading("Whole sweeps (files included)")
        batch_time, batched = timed(lambda: vv.sweep(path, root / "batch", workers=2))
        with dask_executor(workers=2) as executor:
            dask_time, on_dask = timed(lambda: vv.sweep(path, root / "dask", executor=executor))
        subset = root / "alone.json"
        subset.write_text(json.dumps(_first_runs(path, batched.rows[:alone])))
        alone_time, by_one = timed(lambda: vv.sweep(subset, root / "alone", workers=2, batch=False))
        releases = np.array([row["entities[0].parameters.theta1"] for row in batched.rows])
        scipy_time, scipy_finals = scipy_runs(releases[:alone])

        per_run = {
            "batches, process pool": batch_time / runs,
            "batches, Dask LocalCluster": dask_time / runs,
            "alone, process pool": alone_time / alone,
            "SciPy solve_ivp RK45, a loop": scipy_time / alone,
        }
        table = []
        for name, seconds in per_run.items():
            timed_runs = runs if name.startswith("batches") else alone
            table.append(
                [
                    name,
                    str(timed_runs),
                    f"{seconds * timed_runs:.2f} s",
                    f"{seconds * 1e3:.2f} ms",
                    f"{2500 / seconds:.3g}",
                    f"{per_run['alone, process pool'] / seconds:.1f}x",
                ]
            )
        print_table(["runner", "runs", "time", "per run", "system-steps/s", "vs alone"], table)
        batches = {row.get("batch_size") for row in batched.rows}
        print(f"batch sizes: {sorted(b for b in batches if b)}; failed runs: {batched.failed}")
        print(
            f"{runs} runs alone on the pool would take about "
            f"{per_run['alone, process pool'] * runs:.0f} s "
            f"(extrapolated from {alone}); in batches {batch_time:.1f} s"
        )

        heading("Checks")
        same = all(
            {k: a[k] for k in (*FINAL, "max_energy_error", "steps")}
            == {k: b[k] for k in (*FINAL, "max_energy_error", "steps")}
            for a, b in zip(batched.rows[:alone], by_one.rows, strict=True)
        )
        checks.check(same, f"the first {alone} runs alone give the batches' figures bit for bit")
        checks.check(
            [r[FINAL[1]] for r in batched.rows] == [r[FINAL[1]] for r in on_dask.rows],
            "Dask batches give the pool batches' final states bit for bit",
        )
        calm = releases[:alone] < 1.0
        ours = np.array([[row[k] for k in FINAL] for row in batched.rows[:alone]])
        gap = float(np.abs(ours[calm] - scipy_finals[calm]).max()) if calm.any() else math.nan
        checks.check(gap < 1e-5, f"SciPy's final angles agree below 1 rad (max gap {gap:.1e} rad)")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return finish(started, checks)


def _first_runs(path: Path, rows: list[dict]) -> dict:
    """The sweep of ``path`` cut to the runs of ``rows``, with their very values."""
    data = json.loads(path.read_text())
    for parameter in data["parameters"]:
        del parameter["range"]
        parameter["values"] = [row[parameter["path"]] for row in rows]
    return data


if __name__ == "__main__":
    sys.exit(main())
